"""geohaz-calibrate from Python: back-analysis of debris-runout against an observed event, in this
process on one rank (issue #31; the MPI app runs the same library code, docs/calibration.md).
"""
import os

from . import _geohaz
from ._overrides import set_overrides
from .results import read_run, run_in_folder


def run(config, *, set=None, out=None, threads=0, quiet=True, progress=None, progress_every=1):
    """Run `geohaz-calibrate config [--set k=v ...] --out out` in this process (one rank) and return
    its outputs as arrays.

    config   the calibration TOML (calibration.base names the debris-runout case; [[calibration.parameter]]
             the keys with min, max, scale; [observation] the footprint, thalweg, optional deposit,
             run-out point and volume; [score] the weights).
    set      overrides: {"calibration.global_members": 20} or ["calibration.global_members=20"].
    out      None (default): a temporary folder, read back and deleted. A folder: members/ (kept
             for resuming), best.toml, members.csv, acceptable.csv and .svg, sensitivity.csv,
             comparison.tif/.png, thalweg_profile.csv, summary.json stay there; a folder of the
             same calibration is resumed (finished members are not run again).
    threads  OpenMP threads per member (0: keep the current setting).
    progress a callable taking a dict, as for geohaz.ensemble.run: each member's steps (with
             "member", "members_done", "members_planned", the latter an upper bound: the local
             searches may stop early) and "member_finished"; raising in it stops the search
             (Cancel), finished members stay for a resumed run, no outputs are written.
    Returns geohaz.read_run of the output folder ("summary": summary.json; "maps": comparison
    (1 true positive, 2 false positive, 3 false negative) and best_release when the thickness is
    searched; "tables": members, acceptable, sensitivity, thalweg_profile) with "best" (each
    calibrated key → its fitted value, summary["best"]["parameters"]), "best_toml" (the text of
    best.toml) and "out" (the folder, None for a temporary one).
    Raises geohaz.InputError (nothing written), geohaz.IoError.
    """
    return run_in_folder(
        out, "geohaz-calibrate-", lambda folder: _run_into(config, set, folder, threads, quiet, progress, progress_every))


def _run_into(config, set, out, threads, quiet, progress, progress_every):
    _geohaz.calibrate_run(os.fspath(config), set_overrides(set), out, int(threads), bool(quiet), progress,
                          int(progress_every))
    result = read_run(out)
    result["best"] = dict(result["summary"]["best"]["parameters"])
    with open(os.path.join(out, "best.toml")) as f:
        result["best_toml"] = f.read()
    return result


def help_config():
    """The calibration's config keys with unit, default, range and help (as `geohaz-calibrate --help-config`)."""
    return _geohaz.calibrate_help_config()
