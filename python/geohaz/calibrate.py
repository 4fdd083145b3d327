"""geohaz-calibrate from Python: back-analysis of debris-runout against an observed event, in this
process on one rank (issue #31; the MPI app runs the same library code, docs/calibration.md).
"""
import json
import os

from . import _geohaz
from ._overrides import set_overrides


def run(config, *, set=None, out="calibrate-out", threads=0, quiet=True):
    """Run `geohaz-calibrate config [--set k=v ...] --out out` in this process (one rank).

    config   the calibration TOML (calibration.base names the debris-runout case; [[calibration.parameter]]
             the keys with min, max, scale; [observation] the footprint, thalweg, optional deposit,
             run-out point and volume; [score] the weights).
    set      overrides: {"calibration.global_members": 20} or ["calibration.global_members=20"].
    out      the output folder: members/ (kept for resuming), best.toml, members.csv, acceptable.csv
             and .svg, sensitivity.csv, comparison.tif/.png, thalweg_profile.csv, summary.json.
             A folder of the same calibration is resumed (finished members are not run again).
    threads  OpenMP threads per member (0: keep the current setting).
    Returns the summary (dict of summary.json) with "out" added; summary["best"]["parameters"] maps
    each key to its fitted value.
    Raises geohaz.InputError (nothing written), geohaz.IoError.
    """
    text = _geohaz.calibrate_run(os.fspath(config), set_overrides(set), os.fspath(out), int(threads), bool(quiet))
    summary = json.loads(text)
    summary["out"] = os.fspath(out)
    return summary


def help_config():
    """The calibration's config keys with unit, default, range and help (as `geohaz-calibrate --help-config`)."""
    return _geohaz.calibrate_help_config()
