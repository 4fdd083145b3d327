"""dem-avalanche from Python: bonded-disc DEM laboratory tests and rock avalanches.

The run is the app's (libs/dem/run.hpp), made in this process: the same config keys, the same
checks and messages, the same summary and tables (one builder for both), the same outputs when
`out` is given.
"""
import csv
import io
import os
import warnings

import numpy as np

from . import _geohaz
from ._geohaz import InputError
from ._keys import canonical_keys
from ._overrides import set_overrides


def _table(text):
    """A CSV table's text as {column: array}: float64 columns, text columns (ae's mode) as object."""
    rows = list(csv.reader(io.StringIO(text)))
    if not rows:
        return {}
    header, body = rows[0], rows[1:]
    cols = {}
    for k, name in enumerate(header):
        values = [r[k] for r in body]
        try:
            cols[name] = np.array(values, dtype=float)
        except ValueError:
            cols[name] = np.array(values, dtype=object)
    return cols


def run(config, *, set=None, out=None, progress=None, progress_every=1, quiet=True, threads=0):
    """Run a dem-avalanche case and return its summary, tables and final disc fields.

    Arguments mirror `dem-avalanche --config config [--set k=v ...] [--out DIR] [--threads N]`:

    config          the TOML case (data/dem/*.toml; relative paths in it are read beside it).
    set             config overrides: {"bond.tensile_strength": 40e6} or ["bond.tensile_strength=40e6"].
    out             a directory for the app's outputs (summary.json, CSVs, PNGs, snapshots,
                    tessellation, config.resolved.toml), under the app's --out rules; None writes nothing.
    progress        a callable taking a dict: phase ("started", the driver's phases "consolidation",
                    "loading", "settling", "runout", then "finished"), test (lab test name or
                    "avalanche"), time (s), expected_time (s), step, discs; called at the start and
                    end of each test and every `progress_every` records in between.
    quiet           False prints the app's progress line and messages on stderr.
    threads         OpenMP threads (0: keep the current setting, OMP_NUM_THREADS or all cores).

    Returns a dict: "summary" (the figures of summary.json, from the app's builder), "tables"
    ({csv stem: {column: array}}, the app's CSV files: curve_<test>/ae_<test> or runout, ae,
    deposit, fragments; numbers with 9 significant digits as in the files), "discs" ({test name
    or "avalanche": final disc fields: position (n, 2), velocity (n, 2), rotation,
    angular_velocity, radius, mass, id, fragment, intact_bonds, broken_bonds}),
    "resolved_config" (TOML text), "out", "threads".

    Raises InputError (a ValueError: file, key, value, reason; nothing written), SimulationError,
    IoError.
    """
    if config is None:
        raise InputError("--config FILE is required (see dem-avalanche --help)")
    result = _geohaz.dem_run(os.fspath(config), set_overrides(set), os.fspath(out) if out is not None else "",
                             progress, int(progress_every), bool(quiet), int(threads))
    result["tables"] = {stem: _table(text) for stem, text in result.pop("tables_csv")}
    result["summary"] = canonical_keys(result["summary"])
    for w in result["summary"].get("warnings", []):
        warnings.warn(w, RuntimeWarning, stacklevel=2)
    return result


def help_config():
    """Every dem-avalanche config key with unit, default and range (as `dem-avalanche --help-config`)."""
    return _geohaz.dem_help_config()
