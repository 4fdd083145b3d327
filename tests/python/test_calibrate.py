"""geohaz.calibrate: the back-analysis run in-process from Python against the geohaz-calibrate app."""
import json
import tomllib

import numpy as np
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
    seen = []
    r = geohaz.calibrate.run(cfg, out=tmp_path / "py", threads=1, progress=seen.append, progress_every=50)
    s = r["summary"]
    proc = app("geohaz-calibrate", cfg, "--threads", "1", "--quiet", "--out", tmp_path / "app")
    assert proc.returncode == 0, proc.stderr
    a = json.loads((tmp_path / "app" / "summary.json").read_text())
    assert s["best"] == a["best"]
    assert (tmp_path / "py" / "members.csv").read_text() == (tmp_path / "app" / "members.csv").read_text()
    assert set(r["best"]) == {"model.icr"} and r["best"] == s["best"]["parameters"]
    assert 0.1 <= r["best"]["model.icr"] <= 0.25
    assert tomllib.loads(r["best_toml"])["model"]["icr"] == r["best"]["model.icr"]
    assert (tmp_path / "py" / "best.toml").exists() and (tmp_path / "py" / "comparison.png").exists()
    # The comparison map comes back as an array: its cells of class 1, 2, 3 are the best member's
    # TP, FP and FN areas.
    cell = abs(r["geotransform"][1] * r["geotransform"][5])
    for cls, key in ((1, "tp_m2"), (2, "fp_m2"), (3, "fn_m2")):
        area = np.count_nonzero(r["maps"]["comparison"] == cls) * cell
        assert area == pytest.approx(s["best"]["misfit"][key], rel=1e-12), key
    # Progress: every member ran is reported once as finished, in order, with the count.
    finished = [p for p in seen if p["phase"] == "member_finished"]
    assert [p["members_done"] for p in finished] == list(range(1, len(r["tables"]["members"]["member"]) + 1))
    assert all(p["members_done"] <= p["members_planned"] for p in finished)
    assert any(p["phase"] == "running" and p["member"] == 0 and 0 < p["time"] <= p["duration"] for p in seen)
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


def test_raising_in_progress_cancels_and_writes_no_outputs(tmp_path, data):
    cfg = make_event(tmp_path, data)

    class Cancel(Exception):
        pass

    def cancel_in_member_1(p):
        if p.get("member") == 1 and p["phase"] == "running":
            raise Cancel()

    with pytest.raises(Cancel):
        geohaz.calibrate.run(cfg, out=tmp_path / "c", threads=1, progress=cancel_in_member_1, progress_every=5)
    members = sorted(p.name for p in (tmp_path / "c" / "members").iterdir())
    assert members == ["000000"]  # member 0 finished; member 1 left nothing, not even a .partial folder
    assert not (tmp_path / "c" / "best.toml").exists() and not (tmp_path / "c" / "summary.json").exists()
    # The rerun resumes: member 0 is not run again, and the result equals an uninterrupted run's.
    seen = []
    r = geohaz.calibrate.run(cfg, out=tmp_path / "c", threads=1, progress=seen.append, progress_every=1000)
    assert 0 not in [p["member"] for p in seen if p["phase"] == "member_finished"]
    assert r["best"] == geohaz.calibrate.run(cfg, threads=1)["best"]
