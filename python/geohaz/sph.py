"""sph-slope from Python: SPH slope failure with the app's config files and overrides.

The run is the app's (libs/sph/run.hpp), made in this process: the same config keys (read by
libs/sph/src/config.cpp), the same checks and messages, the same outputs when `out` is given.
"""
import os

from . import _geohaz
from ._keys import canonical_keys
from ._overrides import set_overrides


def run(config, *, set=None, out=None, progress=None, progress_every=1, quiet=True, threads=0, particles=True):
    """Run `sph-slope --config config [--set k=v ...] [--out out]` in this process.

    config          the TOML scenario (data/sph/*.toml; relative paths in it are read beside it).
    set             config overrides: {"material[0].cohesion": 5e3} or ["run.end_time=0.5"].
    out             a directory for the app's outputs (series.csv, summary.json, snapshots.h5, PNGs,
                    config.resolved.toml, release.h5 of a section); None writes nothing.
    progress        a callable taking a dict: phase "geostatic" (every 50 steps of the geostatic
                    phase), "trial" (every 50 steps of a strength-reduction trial, with "factor"),
                    then "started", "running" (every `progress_every` main-phase steps), "finished";
                    with time (s of the phase), end_time (s), step and particles.
    quiet           False prints the app's messages and progress lines on stderr.
    threads         OpenMP threads (0: keep the current setting, OMP_NUM_THREADS or all cores).
    particles       False leaves the particle fields out of the result.

    Returns a dict: "summary" (the figures of summary.json, from the same builder), "tables" ({CSV
    stem: {column: float64 array}}: series, structure_forces, stress_strain, surface_final,
    slip_surface; srm_trials, srm_curve, bishop_circle for a strength reduction), "particles"
    (final state, or the failure mechanism of a strength reduction: position, velocity and
    displacement (n, dim), stress (n, 3, 3) in Pa, plastic_strain, pore_pressure (Pa, the prescribed
    u, 0 when dry), density, mass (n,), material_id, kind (0 soil), id), "resolved_config" (TOML text), "out", "threads".

    Raises geohaz.InputError (the app's message, attributes file, key, value, reason; nothing
    written), SimulationError, IoError.
    """
    result = _geohaz.sph_run(os.fspath(config), set_overrides(set), os.fspath(out) if out is not None else "",
                             progress, int(progress_every), bool(quiet), int(threads), bool(particles))
    result["summary"] = canonical_keys(result["summary"])
    return result


def help_config():
    """Every sph-slope config key with unit, default and range (as `sph-slope --help-config`)."""
    return _geohaz.sph_help_config()
