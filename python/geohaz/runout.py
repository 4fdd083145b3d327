"""debris-runout from Python: the depth-averaged particle debris-flow model over a DSM.

The run is the app's (libs/runout/run.hpp), made in this process: the same config keys, the same
checks and messages, the same outputs when `out` is given.
"""
import os
import warnings

from . import _geohaz
from ._keys import canonical_keys
from ._overrides import set_overrides, toml_value

# The app's direct model flags (apps/debris-runout/main.cpp, kDirectFlags) as keyword arguments:
# name → config key. tests/python/test_runout.py checks this table against `debris-runout --help`.
DIRECT_FLAGS = {
    "n": "model.n",
    "icr": "model.icr",
    "friction": "model.friction",
    "mu": "model.mu",
    "xi": "model.xi",
    "density": "model.density",
    "d0": "model.d0",
    "h0": "model.h0",
    "duration": "run.duration",
    "cfl": "numerics.cfl",
    "release_depth": "release.depth",
}


def run(dsm=None, release=None, *, release_from=None, config=None, set=None, out=None, progress=None,
        progress_every=1, quiet=True, threads=0, particles=True, **flags):
    """Run a debris flow over a DSM and return its hazard maps, particles, time series and summary.

    Arguments mirror `debris-runout DSM --release FILE [--config run.toml] [--set k=v] [--FLAG v] --out DIR`:

    dsm, release   the terrain raster and the release (polygons or thickness raster); `release_from`
                   a hand-off file from sph-slope (release.h5) instead. Each overrides the config's
                   terrain.dsm / release.file / release.from.
    config         a TOML case file (relative paths in it are read beside it).
    set            config overrides: {"model.n": 0.08, "run.duration": 300} or ["model.n=0.08"].
    **flags        the app's direct flags: n, icr, friction, mu, xi, density, d0, h0, duration, cfl,
                   release_depth (SI units), e.g. run(dsm, rel, friction="voellmy", mu=0.2, xi=500).
    out            a directory for the app's outputs (GeoTIFF maps, PNGs, series.csv, summary.json,
                   snapshots, config.resolved.toml); None writes nothing.
    progress       a callable taking a dict (phase "started" | "running" | "finished", time,
                   duration, step, particles, mobile_volume), called every `progress_every` steps.
    quiet          False prints the app's progress line on stderr.
    threads        OpenMP threads (0: keep the current setting, OMP_NUM_THREADS or all cores).
    particles      False leaves the particle fields out of the result.

    Returns a dict: "maps" (max_depth, max_speed, max_pressure, deposit, mobile_at_end,
    arrival_time: (ny, nx) float64 arrays, row 0 north, NaN outside the DSM's data and, in
    arrival_time, where the flow never came), "dsm", "release_thickness", "geotransform" (GDAL
    order), "crs_wkt", "summary" (the figures of summary.json), "series" (the columns of
    series.csv), "particles" (every particle field: position (n, 2), speed, depth, volume, ...),
    "resolved_config" (TOML text), "out".

    Raises InputError (nothing written), SimulationError, IoError.
    """
    overrides = set_overrides(set)
    for name, value in flags.items():
        if name not in DIRECT_FLAGS:
            raise TypeError(f"run() got an unexpected keyword argument '{name}' "
                            f"(flags: {', '.join(DIRECT_FLAGS)}; other keys through set=)")
        key = DIRECT_FLAGS[name]
        overrides.append(f"{key}={toml_value(value)}")  # as the app: text quoted, numbers as written
    for value, key in ((dsm, "terrain.dsm"), (release, "release.file"), (release_from, "release.from")):
        if value is not None:
            overrides.append(f"{key}={toml_value(os.fspath(value))}")
    result = _geohaz.runout_run(os.fspath(config) if config is not None else "", overrides,
                                os.fspath(out) if out is not None else "", progress, int(progress_every),
                                bool(quiet), int(threads), bool(particles))
    result["summary"] = canonical_keys(result["summary"])
    result["series"] = canonical_keys(result["series"])
    if result["summary"]["unfinished"]:
        warnings.warn("the run ended at its duration with part of the volume still moving: "
                      "maps['deposit'] holds the resting mass only, maps['mobile_at_end'] the moving "
                      "mass; raise duration", RuntimeWarning, stacklevel=2)
    return result


def help_config():
    """Every debris-runout config key with unit, default and range (as `debris-runout --help-config`)."""
    return _geohaz.runout_help_config()
