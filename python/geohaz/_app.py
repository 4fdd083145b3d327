"""Running an app (sph-slope) in a child process, its exit codes as exceptions.

Its config reader lives in the app's main (apps/sph-slope/main.cpp), so from Python it runs as the
app does; debris-runout and dem-avalanche run in-process (geohaz.runout, geohaz.dem).
"""
import csv
import json
import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from ._geohaz import InputError, IoError, SimulationError
from ._overrides import set_overrides


def find_app(app):
    """The app's executable: $GEOHAZ_BIN_DIR, beside an installed package (<prefix>/bin), the build
    tree (build/apps/<app>/<app>), then PATH."""
    here = Path(__file__).resolve().parent
    candidates = []
    if os.environ.get("GEOHAZ_BIN_DIR"):
        candidates.append(Path(os.environ["GEOHAZ_BIN_DIR"]) / app)
    if len(here.parents) > 3:
        candidates.append(here.parents[3] / "bin" / app)  # <prefix>/lib/python3/dist-packages/geohaz
    candidates.append(here.parents[1] / "apps" / app / app)  # <build>/python/geohaz
    for c in candidates:
        if c.is_file() and os.access(c, os.X_OK):
            return str(c)
    found = shutil.which(app)
    if found:
        return found
    raise FileNotFoundError(f"{app} not found (looked in {', '.join(map(str, candidates))} and PATH); "
                            "set GEOHAZ_BIN_DIR to the folder holding it")


# An InputError's message as errors.cpp composes it: "FILE: 'KEY' = 'VALUE': REASON".
_MESSAGE = re.compile(r"^(?P<file>.+?): '(?P<key>[^']+)'(?: = '(?P<value>.*?)')?: (?P<reason>.+)$", re.S)


def _parts(text):
    """(file, key, value, reason) of an app's error message; None where the message has none."""
    m = _MESSAGE.match(text)
    if not m:
        return None, None, None, text
    return m.group("file"), m.group("key"), m.group("value"), m.group("reason")


def _read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return {}
    header, body = rows[0], rows[1:]
    cols = {}
    for k, name in enumerate(header):
        values = [r[k] for r in body if k < len(r)]
        try:
            cols[name] = np.array(values, dtype=float)
        except ValueError:
            cols[name] = np.array(values, dtype=object)
    return cols


def run_app(app, config, set_, out, threads, quiet):
    """Run `app --config config [--set ...] --out out`; return summary, CSV tables and the output path."""
    if config is None:
        raise InputError(f"--config FILE is required (see {app} --help)")
    exe = find_app(app)
    tmp = None
    if out is None:
        tmp = tempfile.TemporaryDirectory(prefix=f"{app}-")
        out_dir = Path(tmp.name) / "out"
    else:
        out_dir = Path(out)
    cmd = [exe, "--config", os.fspath(config), "--out", str(out_dir), "--threads", str(int(threads))]
    for s in set_overrides(set_):
        cmd += ["--set", s]
    if quiet:
        cmd.append("--quiet")
    try:
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=None if not quiet else subprocess.PIPE,
                              text=True)
        if proc.returncode != 0:
            err = proc.stderr or ""
            message = err.strip().splitlines()[-1] if err.strip() else f"{app} ended with exit code {proc.returncode}"
            for prefix, exc in (("input error: ", InputError), ("simulation stopped: ", SimulationError),
                                ("I/O error: ", IoError), ("system error: ", IoError), ("error: ", RuntimeError)):
                tag = f"{app}: {prefix}"
                if message.startswith(tag):
                    text = message[len(tag):]
                    e = exc(text)
                    e.exit_code = proc.returncode
                    e.file, e.key, e.value, e.reason = _parts(text)
                    raise e
            raise RuntimeError(message)
        result = {"out": None if tmp else str(out_dir), "stdout": proc.stdout}
        summary = out_dir / "summary.json"
        result["summary"] = json.loads(summary.read_text()) if summary.exists() else {}
        result["tables"] = {p.stem: _read_csv(p) for p in sorted(out_dir.glob("*.csv"))}
        return result
    finally:
        if tmp is not None:
            tmp.cleanup()
