"""dem-avalanche from Python: bonded-disc DEM laboratory tests and rock avalanches.

Runs the dem-avalanche executable in a child process (its config reader lives in the app), so there
is no progress callback yet; results are read back from its outputs.
"""
from ._app import run_app


def run(config, *, set=None, out=None, threads=0, quiet=True):
    """Run `dem-avalanche --config config [--set k=v ...] --out out`.

    config   the TOML case (data/dem/*.toml); set: {"bond.tensile_strength": 40e6} or ["key=value"].
    out      the output folder (None: a temporary one, removed after reading).
    Returns {"summary": dict from summary.json, "tables": {csv stem: {column: array}}, "out", "stdout"}.
    Raises geohaz.InputError (exit code 2, the app's message), SimulationError (1), IoError (3).
    """
    return run_app("dem-avalanche", config, set, out, threads, quiet)
