"""geohaz.calibrate: the back-analysis run in-process from Python against the geohaz-calibrate app."""
import json

import pytest

import geohaz
from conftest import app, app_error

CRS = '"crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32654"}}'

CALIBRATE = """
[calibration]
base = "{base}"
global_members = 3
morris_trajectories = 1
local_starts = 1
local_evaluations = 3
[[calibration.parameter]]
key = "model.icr"
min = 0.1
max = 0.25
[observation]
footprint = "{footprint}"
thalweg = "{thalweg}"
"""


def make_event(tmp_path, data):
    """The small valley (coarse particles, one minute) run with i_cr = 0.15: its cells with peak depth
    above 0.1 m as a GeoJSON footprint of cell squares, and a straight thalweg down the valley."""
    base = tmp_path / "base.toml"
    text = (data / "runout/valley_small.toml").read_text()
    text = text.replace('"valley_small', f'"{data}/runout/valley_small').replace("d0 = 2.5", "d0 = 10.0")
    text = text.replace("duration = 600.0", "duration = 60.0")
    base.write_text(text)
    r = geohaz.runout.run(config=base, threads=1)
    x0, dx, _, y0, _, dy = r["geotransform"]
    depth = r["maps"]["max_depth"]
    squares = []
    for row, col in zip(*(depth > 0.1).nonzero()):
        xa, ya = x0 + col * dx, y0 + row * dy
        squares.append(f"[[[{xa},{ya}],[{xa + dx},{ya}],[{xa + dx},{ya + dy}],[{xa},{ya + dy}],[{xa},{ya}]]]")
    assert squares
    (tmp_path / "footprint.geojson").write_text(
        '{"type": "FeatureCollection", ' + CRS + ', "features": [{"type": "Feature", "properties": {}, '
        '"geometry": {"type": "MultiPolygon", "coordinates": [' + ",".join(squares) + "]}}]}")
    ny, nx = depth.shape
    ymid = y0 + 0.5 * ny * dy
    (tmp_path / "thalweg.geojson").write_text(
        '{"type": "FeatureCollection", ' + CRS + ', "features": [{"type": "Feature", "properties": {}, '
        f'"geometry": {{"type": "LineString", "coordinates": [[{x0 + 0.05 * nx * dx}, {ymid}], '
        f'[{x0 + 0.95 * nx * dx}, {ymid}]]}}}}]}}')
    cfg = tmp_path / "cal.toml"
    cfg.write_text(CALIBRATE.format(base=base, footprint=tmp_path / "footprint.geojson",
                                    thalweg=tmp_path / "thalweg.geojson"))
    return cfg


def test_python_and_app_give_the_same_calibration(tmp_path, data):
    cfg = make_event(tmp_path, data)
    s = geohaz.calibrate.run(cfg, out=tmp_path / "py", threads=1)
    proc = app("geohaz-calibrate", cfg, "--threads", "1", "--quiet", "--out", tmp_path / "app")
    assert proc.returncode == 0, proc.stderr
    a = json.loads((tmp_path / "app" / "summary.json").read_text())
    assert s["best"] == a["best"]
    assert (tmp_path / "py" / "members.csv").read_text() == (tmp_path / "app" / "members.csv").read_text()
    assert set(s["best"]["parameters"]) == {"model.icr"}
    assert 0.1 <= s["best"]["parameters"]["model.icr"] <= 0.25
    assert (tmp_path / "py" / "best.toml").exists() and (tmp_path / "py" / "comparison.png").exists()
    assert "calibration.global_members" in geohaz.calibrate.help_config()


def test_bad_bounds_raise_input_error_naming_the_key_and_write_nothing(tmp_path, data):
    cfg = make_event(tmp_path, data)
    with pytest.raises(geohaz.InputError) as e:
        geohaz.calibrate.run(cfg, set={"calibration.parameter[0].min": 0.3}, out=tmp_path / "never")
    assert "calibration.parameter[0].min" in str(e.value)
    assert not (tmp_path / "never").exists()
    proc = app("geohaz-calibrate", cfg, "--set", "calibration.parameter[0].min=0.3", "--out", tmp_path / "never")
    assert "calibration.parameter[0].min" in app_error(proc, "geohaz-calibrate")
    assert not (tmp_path / "never").exists()
