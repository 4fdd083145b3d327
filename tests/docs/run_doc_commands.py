#!/usr/bin/env python3
"""Run the shell command blocks of README.md, data/README.md and docs/*.md as a reader would
(issue #29 item 2): every command of a ```sh / ```bash block, from a folder that looks like the
repository root (links to data/ and build/, the apps' folders on PATH as after an install), one
after the other, each must exit 0.

Skip rules (printed with the reason for every command skipped):
  1. A block right after the HTML comment  <!-- doc-commands: skip: REASON -->  (e.g. a run of
     more than a minute, or one the demo check already runs) is not run.
  2. data/README.md's tables: the commands in a row's first cell (inline code starting with
     build/apps/) run when the row's time column says seconds below 60 ("~5 s"); rows whose time
     is in minutes, a range reaching 60 s or more, or a reference elsewhere are skipped.
  3. Commands whose first word is in SKIPPED_PROGRAMS below: they build, install, change the
     machine or need a cluster, and CI runs them itself (scripts/test, scripts/demo) or cannot.
Usage: run_doc_commands.py SOURCE_DIR BUILD_DIR
"""
import os
import re
import shlex
import subprocess
import sys
import tempfile
import time

SKIPPED_PROGRAMS = {
    "scripts/demo": "builds and runs the whole demo (CI runs it after the tests)",
    "scripts/test": "builds and runs the test suite (this test is part of it)",
    "scripts/validate": "the long validation runs (hours)",
    "scripts/build": "builds (done before the tests)",
    "cmake": "installs the build (package_consumer tests it)",
    "cd": "changes folder for a packaging command (package_deb tests cpack)",
    "sudo": "changes the machine",
    "git": "needs the network",
    "mpirun": "more ranks than a test may take (runout_ensemble_app tests mpirun -np 2)",
    "srun": "needs a Slurm cluster",
    "export": "part of a cluster job script",
    "#!/bin/bash": "a job script",
}
SKIP_MARK = re.compile(r"<!--\s*doc-commands:\s*skip:\s*(.*?)\s*-->\s*$")
FENCE = re.compile(r"^```(sh|bash|shell)\s*$")


def blocks(path):
    """(line number, skip reason or None, [commands]) of each shell block of a Markdown file."""
    lines = open(path, encoding="utf-8").read().splitlines()
    out, i, pending = [], 0, None
    while i < len(lines):
        m = SKIP_MARK.search(lines[i])
        if m:
            pending = m.group(1)
        elif FENCE.match(lines[i]):
            start, cmds, cur = i + 1, [], ""
            i += 1
            while i < len(lines) and not lines[i].startswith("```"):
                text = lines[i]
                if not cur and text.lstrip().startswith("#") and not text.startswith("#!"):
                    i += 1
                    continue
                text = re.sub(r"\s+#(?![^\s]*[\"']).*$", "", text) if not text.startswith("#!") else text
                if text.rstrip().endswith("\\"):
                    cur += text.rstrip()[:-1] + " "
                else:
                    cur += text
                    if cur.strip():
                        cmds.append(cur.strip())
                    cur = ""
                i += 1
            out.append((start, pending, cmds))
            pending = None
        elif lines[i].strip():
            pending = None if not lines[i].lstrip().startswith("<!--") else pending
        i += 1
    return out


def table_commands(path):
    """(line number, skip reason or None, [command]) of each data/README.md table row with a command."""
    out = []
    for n, row in enumerate(open(path, encoding="utf-8").read().splitlines(), 1):
        if not row.startswith("| `build/apps/"):
            continue
        cells = [c.strip() for c in row.strip().strip("|").split("|")]
        cmd = re.match(r"`([^`]*)`", cells[0]).group(1)
        secs = [float(x) for x in re.findall(r"(\d+(?:\.\d+)?)\s*s\b", cells[-1])]
        long_ = not secs or "min" in cells[-1] or max(secs) >= 60 or len(cells) < 3
        out.append((n, f"the table gives its time as '{cells[-1][:40]}'" if long_ else None, [cmd]))
    return out


def main():
    src, build = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    files = ["README.md", "data/README.md"] + sorted(
        "docs/" + f for f in os.listdir(os.path.join(src, "docs")) if f.endswith(".md"))
    root = tempfile.mkdtemp(prefix="geohaz_doc_commands_")
    for name in ("data", "docs", "scripts"):
        os.symlink(os.path.join(src, name), os.path.join(root, name))
    os.symlink(build, os.path.join(root, "build"))
    apps = os.path.join(build, "apps")
    env = dict(os.environ, LC_ALL="C.UTF-8")
    env["PATH"] = os.pathsep.join(
        [os.path.join(apps, a) for a in sorted(os.listdir(apps)) if os.path.isdir(os.path.join(apps, a))]
        + [env.get("PATH", "")])
    ran = failed = skipped = 0
    for f in files:
        found = blocks(os.path.join(src, f))
        if f == "data/README.md":
            found += table_commands(os.path.join(src, f))
        for line, reason, cmds in found:
            for cmd in cmds:
                first = cmd.split()[0]
                why = reason or SKIPPED_PROGRAMS.get(first)
                if why:
                    skipped += 1
                    print(f"SKIP {f}:{line}: {cmd}\n     ({why})")
                    continue
                t0 = time.time()
                r = subprocess.run(["bash", "-c", cmd], cwd=root, env=env, stdout=subprocess.PIPE,
                                   stderr=subprocess.STDOUT, text=True, timeout=300)
                ran += 1
                status = "ok" if r.returncode == 0 else f"FAILED (exit {r.returncode})"
                print(f"RUN  {f}:{line}: {cmd}\n     {status} in {time.time() - t0:.1f} s")
                if r.returncode != 0:
                    failed += 1
                    print(r.stdout[-3000:])
    print(f"{ran - failed} passed, {failed} failed, {skipped} skipped")
    subprocess.run(["rm", "-rf", root])
    return 1 if failed or ran == 0 else 0


if __name__ == "__main__":
    sys.exit(main())
