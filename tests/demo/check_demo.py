#!/usr/bin/env python3
"""Check what a user sees after `scripts/demo` (issue #29 item 2; run by .ci/run after the demo).

Reads the demo's results folder (default results/demo) and fails, with one line per broken promise,
when:
  - a step's summary is missing (the demo's steps each exit 0 under `set -e`; a missing summary means
    a step did not finish);
  - the control of step 1 is not met: Bishop's factor of safety of the section (static, dry, peak
    strength) below 1.2;
  - the chain does not hold: the volume sph-slope handed over, the volume debris-runout read and the
    volume it seeded differ by more than 1e-9 (relative);
  - the handed volume lies outside the range documented in docs/workflow.md (the DEMO_VOLUME_RANGE
    line there, so the docs and this check cannot drift apart);
  - the report page does not open in headless Chromium with every image decoded and no error (the
    page's own #page-check marks, as tests/report/test_report_browser.cpp reads them);
  - the report's PDF (report.pdf, the page printed by Chromium for a client) is missing, is not a PDF,
    has a page that is not A4, or has fewer pages than the overview plus one per run (each run
    starts a new page, docs/report.md).
Exit 0 when all hold, 1 otherwise. Uses only the Python standard library and Debian's chromium.
"""
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def fail(msg, problems):
    problems.append(msg)
    print(f"check-demo: FAIL: {msg}", file=sys.stderr)


def load(path, problems):
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError) as e:
        fail(f"{path}: cannot read the summary ({e})", problems)
        return None


def documented_range():
    """The handed-volume range written in docs/workflow.md as `DEMO_VOLUME_RANGE: lo–hi m³`."""
    text = (ROOT / "docs" / "workflow.md").read_text()
    m = re.search(r"DEMO_VOLUME_RANGE:\s*([0-9,]+)\s*(?:–|-|to)\s*([0-9,]+)\s*m³", text)
    if not m:
        raise SystemExit("check-demo: docs/workflow.md has no 'DEMO_VOLUME_RANGE: lo–hi m³' line")
    return float(m.group(1).replace(",", "")), float(m.group(2).replace(",", ""))


def page_marks(html, problems):
    chromium = next((shutil.which(n) for n in ("chromium", "chromium-browser") if shutil.which(n)), None)
    if chromium is None:
        fail("chromium is not installed (scripts/setup installs it): the report page was not opened", problems)
        return
    with tempfile.TemporaryDirectory() as profile:
        env = dict(os.environ, DBUS_SESSION_BUS_ADDRESS="disabled:")
        r = subprocess.run(
            [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             f"--user-data-dir={profile}", "--virtual-time-budget=20000", "--enable-logging=stderr",
             "--v=0", "--dump-dom", html.as_uri()],
            capture_output=True, text=True, env=env, timeout=300)
    if r.returncode != 0:
        fail(f"chromium exited {r.returncode} on {html}: {r.stderr[-2000:]}", problems)
        return
    tag = re.search(r'<div id="page-check"[^>]*>', r.stdout)
    if not tag:
        fail(f"{html}: the page has no #page-check mark (did its script run?)", problems)
        return
    marks = dict(re.findall(r'data-(\w+)="(\d+)"', tag.group(0)))
    images, decoded, errors = (int(marks.get(k, -1)) for k in ("images", "decoded", "errors"))
    if images <= 0 or decoded != images or errors != 0:
        fail(f"{html}: {decoded} of {images} images decoded, {errors} errors", problems)
    if ":CONSOLE" in r.stderr:
        fail(f"{html}: the page logged to the console: {r.stderr[-2000:]}", problems)
    print(f"check-demo: report page: {decoded} of {images} images decoded, no error")


A4_PT = (595.28, 841.89)  # ISO 216, 210 mm x 297 mm in PostScript points


def pdf_pages(pdf, runs, problems):
    """The page tree as Chromium's PDF writer (Skia) leaves it: one uncompressed page dictionary
    with its /MediaBox per page, so the standard library suffices (the report's own test uses
    poppler-utils, tests/report/test_report_browser.cpp)."""
    if not pdf.is_file():
        fail(f"{pdf} was not written", problems)
        return
    data = pdf.read_bytes()
    if not data.startswith(b"%PDF-"):
        fail(f"{pdf}: not a PDF file (starts with {data[:8]!r})", problems)
        return
    pages = len(re.findall(rb"/Type\s*/Page(?![a-zA-Z])", data))
    boxes = [tuple(float(v) for v in m.split()) for m in re.findall(rb"/MediaBox\s*\[([^\]]*)\]", data)]
    not_a4 = [b for b in boxes if len(b) != 4 or abs(b[2] - b[0] - A4_PT[0]) > 1.0 or abs(b[3] - b[1] - A4_PT[1]) > 1.0]
    if pages < 1 + runs:
        fail(f"{pdf}: {pages} pages, fewer than the overview plus one per run ({1 + runs})", problems)
    elif not boxes or not_a4:
        fail(f"{pdf}: page sizes {sorted(set(not_a4 or boxes))} are not A4 ({A4_PT[0]} x {A4_PT[1]} pt)", problems)
    else:
        print(f"check-demo: report PDF: {pages} A4 pages, {len(data) / 1e6:.1f} MB")


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else ROOT / "results" / "demo").resolve()
    problems = []
    s1 = load(out / "1-slope-failure" / "summary.json", problems)
    s2 = load(out / "2-runout" / "summary.json", problems)
    for step in ("3-runout-processes", "4-rock-biaxial", "5-rock-avalanche"):
        load(out / step / "summary.json", problems)
    if s1 is not None:
        bishop = s1.get("bishop", {}).get("factor")
        if bishop is None:
            fail("step 1 reports no Bishop factor of safety for the section", problems)
        elif bishop < 1.2:
            fail(f"step 1: Bishop's static factor of safety {bishop:.3f} < 1.2 (the control margin)", problems)
        else:
            print(f"check-demo: step 1 Bishop factor of safety (static) {bishop:.3f} >= 1.2")
    if s1 is not None and s2 is not None:
        handed = s1.get("release", {}).get("total_volume_m3", 0.0)
        read = s2.get("volumes_m3", {}).get("release_read", 0.0)
        seeded = s2.get("volumes_m3", {}).get("seeded", 0.0)
        for name, v in (("read by debris-runout", read), ("seeded by debris-runout", seeded)):
            if not abs(v - handed) <= 1e-9 * max(abs(handed), 1.0):
                fail(f"volume {name} {v!r} m³ differs from the {handed!r} m³ sph-slope handed over", problems)
        lo, hi = documented_range()
        if not lo <= handed <= hi:
            fail(f"handed volume {handed:.0f} m³ outside the documented {lo:.0f}–{hi:.0f} m³", problems)
        else:
            print(f"check-demo: handed {handed:.1f} m³ = read {read:.1f} = seeded {seeded:.1f} m³, "
                  f"within the documented {lo:.0f}–{hi:.0f} m³")
    html = out / "report.html"
    if not html.is_file():
        fail(f"{html} was not written", problems)
    else:
        page_marks(html, problems)
    runs = sum(1 for d in out.iterdir() if (d / "summary.json").is_file()) if out.is_dir() else 0
    pdf_pages(out / "report.pdf", runs, problems)
    if problems:
        print(f"check-demo: {len(problems)} problem(s) in {out}", file=sys.stderr)
        return 1
    print(f"check-demo: the demo in {out} holds")
    return 0


if __name__ == "__main__":
    sys.exit(main())
