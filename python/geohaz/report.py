"""geohaz-report from Python: the report page (and its PDF) of one or several run folders, written by
the same library as the app (docs/report.md).
"""
import os

from . import _geohaz


def write(results, *, title="geohaz results", pdf=False):
    """Write `results`/report.html (and report_files/) as `geohaz-report results --title title [--pdf]`
    does, from every run folder in `results` (itself or a sub-folder up to two levels deep holding a
    summary.json: any geohaz app's --out folder, an ensemble's, a calibration's).

    pdf      also print the page to `results`/report.pdf with headless Chromium (A4).
    Returns {"html": path, "pdf": path or None}. Raises geohaz.InputError when there is no run in
    `results` or a summary.json does not parse (nothing written), geohaz.IoError when the PDF cannot
    be made (no Chromium: checked before anything is written).
    """
    html, pdf_path = _geohaz.report_write(os.fspath(results), str(title), bool(pdf))
    return {"html": html, "pdf": pdf_path}
