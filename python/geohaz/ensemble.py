"""geohaz-ensemble from Python: an ensemble of debris-runout runs and its probability maps, in this
process on one rank (issue #20; the MPI app runs the same library code, docs/ensemble.md).
"""
import os

from . import _geohaz
from ._overrides import set_overrides
from .results import read_run, run_in_folder


def run(config, *, set=None, out=None, threads=0, quiet=True, progress=None, progress_every=1):
    """Run `geohaz-ensemble config [--set k=v ...] --out out` in this process (one rank) and return
    its products as arrays.

    config   the ensemble TOML (ensemble.base names the debris-runout case).
    set      overrides: {"ensemble.members": 20} or ["ensemble.members=20"].
    out      None (default): the run goes to a temporary folder, read back and deleted, so nothing
             is left behind. A folder: members/ (kept for resuming), the probability, mean and
             percentile GeoTIFFs, members.csv, the plots and summary.json stay there; a folder of
             the same ensemble is resumed (finished members are skipped).
    threads  OpenMP threads per member (0: keep the current setting).
    progress a callable taking a dict, called every `progress_every` steps of each member with the
             keys of geohaz.runout.run's progress (phase, time, duration, step, particles,
             mobile_volume) and "member", "members_done", "members_planned"; after each member
             with phase "member_finished" and "ok". An exception raised in it stops the ensemble
             (Cancel): finished members stay in `out` for a resumed run, no products are written,
             and the exception propagates.
    Returns geohaz.read_run of the output folder: "summary" (summary.json), "maps" (every
    probability, mean and percentile map as (ny, nx) arrays), "tables" (members.csv, ...),
    "units", "geotransform", "crs_wkt", and "out" (the folder, None for a temporary one).
    Raises geohaz.InputError (nothing written), geohaz.IoError.
    """
    return run_in_folder(
        out, "geohaz-ensemble-", lambda folder: _run_into(config, set, folder, threads, quiet, progress, progress_every))


def _run_into(config, set, out, threads, quiet, progress, progress_every):
    _geohaz.ensemble_run(os.fspath(config), set_overrides(set), out, int(threads), bool(quiet), progress,
                         int(progress_every))
    return read_run(out)


def help_config():
    """The ensemble's config keys with unit, default, range and help (as `geohaz-ensemble --help-config`)."""
    return _geohaz.ensemble_help_config()
