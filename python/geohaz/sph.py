"""sph-slope from Python: SPH slope failure with the app's config files and overrides.

Runs the sph-slope executable in a child process (its config reader lives in the app), so there is
no progress callback yet; results are read back from its outputs.
"""
from ._app import run_app


def run(config, *, set=None, out=None, threads=0, quiet=True):
    """Run `sph-slope --config config [--set k=v ...] --out out`.

    config   the TOML scenario (data/sph/*.toml); set: {"material[0].cohesion": 5e3} or ["key=value"].
    out      the output folder (None: a temporary one, removed after reading).
    Returns {"summary": dict from summary.json, "tables": {csv stem: {column: array}}, "out", "stdout"}.
    Raises geohaz.InputError (exit code 2, the app's message), SimulationError (1), IoError (3).
    """
    return run_app("sph-slope", config, set, out, threads, quiet)
