"""Reading an existing output folder of any geohaz app back as NumPy arrays (geohaz.read_run)."""
import csv
import json
import os
import tempfile
from pathlib import Path

import numpy as np

from . import _geohaz
from ._keys import canonical, canonical_keys, unit_of


def read_table(path):
    """A CSV file as {column: array}: float64 columns, text columns as object arrays; column names
    under the naming rule (geohaz._keys)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return canonical_keys({})
    header, body = rows[0], rows[1:]
    cols = {}
    for k, name in enumerate(header):
        values = [r[k] if k < len(r) else "" for r in body]
        try:
            cols[name] = np.array(values, dtype=float)
        except ValueError:
            cols[name] = np.array(values, dtype=object)
    return canonical_keys(cols)


def read_raster(path):
    """Band 1 of a raster through the apps' own reader (GDAL): a dict with "values" ((ny, nx)
    float64, row 0 north, NaN at nodata), "geotransform" (GDAL order), "crs_wkt", "nodata",
    "unit" and "description" (as the apps write them into every GeoTIFF)."""
    return _geohaz.read_raster(os.fspath(path))


def read_run(folder):
    """Everything an app (or geohaz.*.run(out=...)) wrote into `folder`, as arrays and dicts.

    Returns a dict:
      "summary"          summary.json, keys under the naming rule (old spellings still answer)
      "maps"             {name: (ny, nx) float64 array} for every GeoTIFF in the folder (not in
                         subfolders such as an ensemble's members/), NaN at nodata
      "tables"           {CSV stem: {column: array}} for every CSV file in the folder
      "series"           tables["series"] when there is a series.csv (debris-runout, sph-slope)
      "units"            {"maps": {name: unit}, "tables": {stem: {column: unit}}}: a map's unit
                         from its GeoTIFF band, a column's from its name's suffix ("" if none)
      "grids"            {name: {"geotransform", "crs_wkt", "nodata", "description"}} per map
      "geotransform", "crs_wkt"  the grid shared by all maps (None when they differ or none)
      "resolved_config"  the text of config.resolved.toml (None if absent)
      "folder"           the folder as given
    Raises FileNotFoundError when `folder` is not a folder, geohaz.InputError for an unreadable
    raster (the message names the file).
    """
    folder = Path(folder)
    if not folder.is_dir():
        raise FileNotFoundError(f"read_run: no output folder '{folder}'")
    summary_path = folder / "summary.json"
    summary = canonical_keys(json.loads(summary_path.read_text())) if summary_path.is_file() else canonical_keys({})
    maps, grids, map_units = {}, {}, {}
    for tif in sorted(folder.glob("*.tif")):
        r = read_raster(tif)
        maps[tif.stem] = r.pop("values")
        map_units[tif.stem] = r.pop("unit")
        grids[tif.stem] = r
    tables = {csv_path.stem: read_table(csv_path) for csv_path in sorted(folder.glob("*.csv"))}
    shared = {(tuple(g["geotransform"]), g["crs_wkt"]) for g in grids.values()}
    geotransform, crs_wkt = next(iter(shared)) if len(shared) == 1 else (None, None)
    config = folder / "config.resolved.toml"
    return {
        "summary": summary,
        "maps": maps,
        "tables": tables,
        "series": tables.get("series"),
        "units": {"maps": map_units,
                  "tables": {stem: {c: unit_of(c) for c in cols} for stem, cols in tables.items()}},
        "grids": grids,
        "geotransform": geotransform,
        "crs_wkt": crs_wkt,
        "resolved_config": config.read_text() if config.is_file() else None,
        "folder": os.fspath(folder),
    }


__all__ = ["read_run", "read_raster", "read_table", "canonical"]


def run_in_folder(out, prefix, run_into):
    """Run `run_into(folder)` (which returns read_run of it) in `out`, or, when out is None, in a
    temporary folder named with `prefix` that is deleted afterwards; the result's "out" is the
    folder (None for a temporary one). Shared by ensemble.run and calibrate.run."""
    if out is None:
        with tempfile.TemporaryDirectory(prefix=prefix) as tmp:
            result = run_into(os.path.join(tmp, "out"))
        result["out"] = None
        return result
    result = run_into(os.fspath(out))
    result["out"] = os.fspath(out)
    return result
