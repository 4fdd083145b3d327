"""geohaz-ensemble from Python: an ensemble of debris-runout runs and its probability maps, in this
process on one rank (issue #20; the MPI app runs the same library code, docs/ensemble.md).
"""
import json
import os

from . import _geohaz
from ._overrides import set_overrides


def run(config, *, set=None, out="ensemble-out", threads=0, quiet=True):
    """Run `geohaz-ensemble config [--set k=v ...] --out out` in this process (one rank).

    config   the ensemble TOML (ensemble.base names the debris-runout case).
    set      overrides: {"ensemble.members": 20} or ["ensemble.members=20"].
    out      the output folder: members/ (kept for resuming), the probability, mean and percentile
             GeoTIFFs, members.csv, the plots and summary.json. A folder of the same ensemble is
             resumed (finished members are skipped).
    threads  OpenMP threads per member (0: keep the current setting).
    Returns the summary (dict of summary.json) with "out" added.
    Raises geohaz.InputError (nothing written), geohaz.IoError.
    """
    text = _geohaz.ensemble_run(os.fspath(config), set_overrides(set), os.fspath(out), int(threads), bool(quiet))
    summary = json.loads(text)
    summary["out"] = os.fspath(out)
    return summary


def help_config():
    """The ensemble's config keys with unit, default, range and help (as `geohaz-ensemble --help-config`)."""
    return _geohaz.ensemble_help_config()
