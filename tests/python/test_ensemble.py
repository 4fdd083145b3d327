"""geohaz.ensemble: the ensemble run in-process from Python against the geohaz-ensemble app."""
import json

import numpy as np
import pytest

import geohaz
from conftest import app, app_error

# Three members of the small valley with coarse particles and a short duration (a few seconds).
ENSEMBLE = """
[ensemble]
base = "{base}"
members = 3
seed = 5
[[ensemble.parameter]]
key = "model.icr"
distribution = "uniform"
min = 0.12
max = 0.2
[[ensemble.parameter]]
key = "model.d0"
distribution = "fixed"
value = 10.0
[[ensemble.parameter]]
key = "run.duration"
distribution = "fixed"
value = 60.0
[products]
depth_thresholds = [0.5]
"""


def test_python_and_app_give_the_same_ensemble(tmp_path, data):
    cfg = tmp_path / "ens.toml"
    cfg.write_text(ENSEMBLE.format(base=data / "runout/valley_small.toml"))
    r = geohaz.ensemble.run(cfg, out=tmp_path / "py", threads=1)
    s = r["summary"]
    proc = app("geohaz-ensemble", cfg, "--threads", "1", "--quiet", "--out", tmp_path / "app")
    assert proc.returncode == 0, proc.stderr
    a = json.loads((tmp_path / "app" / "summary.json").read_text())
    assert s["succeeded"] == a["succeeded"] == 3
    # The same members, bit for bit: the same run-out statistics and the same probability map.
    assert s["runout_length_along_path_m"] == a["runout_length_along_path_m"]
    assert (tmp_path / "py" / "prob_max_depth_gt_0.5m.tif").read_bytes() == \
        (tmp_path / "app" / "prob_max_depth_gt_0.5m.tif").read_bytes()
    # The products come back as arrays: the probability map is the GeoTIFF on disk.
    prob = geohaz.read_raster(tmp_path / "app" / "prob_max_depth_gt_0.5m.tif")["values"]
    np.testing.assert_array_equal(r["maps"]["prob_max_depth_gt_0.5m"], prob)
    assert r["out"] == str(tmp_path / "py")
    assert "ensemble.sampling" in geohaz.ensemble.help_config()


def test_without_a_folder_nothing_is_left_behind(tmp_path, data, monkeypatch):
    cfg = tmp_path / "ens.toml"
    cfg.write_text(ENSEMBLE.format(base=data / "runout/valley_small.toml").replace("members = 3", "members = 2"))
    monkeypatch.chdir(tmp_path)
    r = geohaz.ensemble.run(cfg, threads=1)
    assert r["out"] is None and r["summary"]["succeeded"] == 2
    assert np.nanmax(r["maps"]["prob_max_depth_gt_0.5m"]) <= 1.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ens.toml"]  # no ensemble-out


def test_bad_input_raises_the_apps_message_and_writes_nothing(tmp_path, data):
    cfg = tmp_path / "ens.toml"
    cfg.write_text(ENSEMBLE.format(base=data / "runout/valley_small.toml").replace("min = 0.12", "min = 0.3"))
    expected = app_error(app("geohaz-ensemble", cfg, "--out", tmp_path / "app"), "geohaz-ensemble")
    with pytest.raises(geohaz.InputError) as e:
        geohaz.ensemble.run(cfg, out=tmp_path / "py")
    assert str(e.value) == expected
    assert e.value.key == "ensemble.parameter[0].min"
    assert not (tmp_path / "py").exists() and not (tmp_path / "app").exists()


def test_progress_sees_every_member_and_raising_in_it_cancels(tmp_path, data):
    cfg = tmp_path / "ens.toml"
    cfg.write_text(ENSEMBLE.format(base=data / "runout/valley_small.toml"))
    seen = []
    geohaz.ensemble.run(cfg, out=tmp_path / "full", threads=1, progress=seen.append, progress_every=10)
    finished = [(p["member"], p["members_done"], p["members_planned"], p["ok"]) for p in seen
                if p["phase"] == "member_finished"]
    assert finished == [(0, 1, 3, True), (1, 2, 3, True), (2, 3, 3, True)]
    running = [p for p in seen if p["phase"] == "running"]
    assert running and all(p["step"] % 10 == 0 and 0 < p["time"] <= p["duration"] == 60.0 for p in running)
    # Cancel in member 1: member 0 stays, member 1 leaves nothing, no products; the rerun resumes
    # and gives the uninterrupted run's probability map, byte for byte.

    class Cancel(Exception):
        pass

    def cancel(p):
        if p.get("member") == 1 and p["phase"] == "running":
            raise Cancel()

    with pytest.raises(Cancel):
        geohaz.ensemble.run(cfg, out=tmp_path / "c", threads=1, progress=cancel, progress_every=5)
    assert sorted(p.name for p in (tmp_path / "c" / "members").iterdir()) == ["000000"]
    assert not list((tmp_path / "c").glob("*.tif")) and not (tmp_path / "c" / "summary.json").exists()
    again = []
    geohaz.ensemble.run(cfg, out=tmp_path / "c", threads=1, progress=again.append, progress_every=1000)
    assert [p["member"] for p in again if p["phase"] == "member_finished"] == [1, 2]
    assert (tmp_path / "c" / "prob_max_depth_gt_0.5m.tif").read_bytes() == \
        (tmp_path / "full" / "prob_max_depth_gt_0.5m.tif").read_bytes()
