"""geohaz from Python: the landslide models of geohaz run in-process, results as NumPy arrays.

    import geohaz
    r = geohaz.runout.run("avaAlr.tif", release="relAlr.shp", n=0.06, h0=0.25)
    r["maps"]["max_speed"]        # (ny, nx) array on the DSM grid, NaN outside the DSM's data
    r["summary"]["runout_length_along_path_m"]
    run = geohaz.read_run("out")   # any app's output folder: summary, every GeoTIFF and CSV as arrays

Bad input raises geohaz.InputError (a ValueError) with the message the apps print and the
attributes file, key, value and reason; nothing is written. A run that blows up raises
geohaz.SimulationError (a RuntimeError), a failed write geohaz.IoError (an OSError).
See docs/python.md.
"""
from ._geohaz import __version__, InputError, IoError, SimulationError
from . import runout, sph, dem, ensemble, calibrate, report
from .results import read_run, read_raster

__all__ = ["__version__", "InputError", "IoError", "SimulationError", "runout", "sph", "dem", "ensemble", "calibrate",
           "report", "read_run", "read_raster"]
