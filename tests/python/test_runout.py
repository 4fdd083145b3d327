"""geohaz.runout: the debris-runout run from Python against the app on the same case."""
import json
import math
import re

import numpy as np
import pytest

import geohaz
from conftest import app, app_error

CASE = "runout/valley_small.toml"  # 400 × 200 cells of 2.5 m, ~1,600 particles


def test_keyword_flags_are_the_apps_direct_flags():
    # Every "--flag ... sets key" line of debris-runout --help, and nothing else.
    help_text = app("debris-runout", "--help").stdout
    block = help_text[help_text.index("Options"):].split("\n\n")[0]
    options = re.split(r"\n\s+(?=-)", block)  # one entry per option, continuation lines included
    flags = {}
    for o in options:
        m = re.match(r"--([a-z0-9-]+) arg\b.*\bsets\s+([a-z_]+\.[a-z0-9_]+)\s*$", " ".join(o.split()))
        if m:
            flags[m.group(1)] = m.group(2)
    assert len(flags) == 11, flags
    assert {k.replace("-", "_"): v for k, v in flags.items()} == geohaz.runout.DIRECT_FLAGS


@pytest.mark.parametrize("python_args, app_args", [
    ({"n": 1.0}, ["--n", "1.0"]),                                  # out of range
    ({"set": {"model.nn": 1}}, ["--set", "model.nn=1"]),         # unknown key
    ({"friction": "voellmy", "n": 0.05}, ["--friction", "voellmy", "--n", "0.05"]),  # key of another law
    ({"set": ["run.duration=-1"]}, ["--set", "run.duration=-1"]),
])
def test_bad_input_raises_the_apps_message_and_writes_nothing(tmp_path, data, python_args, app_args):
    dsm, rel = data / "runout/valley_small.tif", data / "runout/valley_small_release.tif"
    expected = app_error(app("debris-runout", dsm, "--release", rel, *app_args, "--out", tmp_path / "app"),
                         "debris-runout")
    with pytest.raises(geohaz.InputError) as e:
        geohaz.runout.run(dsm, rel, out=tmp_path / "py", **python_args)
    assert str(e.value) == expected
    assert isinstance(e.value, ValueError)
    assert not (tmp_path / "py").exists() and not (tmp_path / "app").exists()


def test_input_error_carries_file_key_and_value(tmp_path, data):
    with pytest.raises(geohaz.InputError) as e:
        geohaz.runout.run(config=data / CASE, set={"model.h0": -2.0}, out=tmp_path / "x")
    assert (e.value.file, e.value.key, e.value.value) == ("command line (--set)", "model.h0", "-2.0")
    assert e.value.reason in str(e.value)
    missing = tmp_path / "nowhere.tif"
    expected = app_error(app("debris-runout", missing, "--release", data / "runout/valley_small_release.tif"),
                         "debris-runout")
    with pytest.raises(geohaz.InputError, match=re.escape(expected)):
        geohaz.runout.run(missing, data / "runout/valley_small_release.tif")


def test_a_run_from_python_matches_the_app_and_writes_the_same_outputs(tmp_path, data):
    proc = app("debris-runout", "--config", data / CASE, "--duration", "20", "--threads", "1", "--quiet",
               "--out", tmp_path / "app")
    assert proc.returncode == 0, proc.stderr
    with pytest.warns(RuntimeWarning, match="still moving"):  # 20 s: the flow is still on its way
        r = geohaz.runout.run(config=data / CASE, duration=20, threads=1, out=tmp_path / "py")
    assert sorted(p.name for p in (tmp_path / "py").iterdir()) == sorted(p.name for p in (tmp_path / "app").iterdir())
    a = json.loads((tmp_path / "app/summary.json").read_text())
    p = json.loads((tmp_path / "py/summary.json").read_text())
    for k in ("wall_time_s",):
        a.pop(k), p.pop(k)
    assert p == a  # the same run, bit for bit on one thread
    s = r["summary"]
    assert s["steps"] == a["steps"] and s["particles_released"] == a["particles_released"]
    assert s["runout_length_along_path_m"] == a["runout_length_along_path_m"]
    # summary.json may carry more volumes (terms of processes) than the dict; the shared ones agree.
    assert len(s["volumes_m3"]) >= 7
    assert s["volumes_m3"] == {k: a["volumes_m3"][k] for k in s["volumes_m3"]}
    assert s["max_speed_m_per_s"] == a["max_speed_m_per_s"] > 1.0
    assert s["ended_by"] == "duration reached" and s["simulated_time_s"] == pytest.approx(20.0, abs=1e-9)
    assert (tmp_path / "py/config.resolved.toml").read_text() == r["resolved_config"]


@pytest.mark.filterwarnings("ignore:the run ended at its duration")
def test_maps_are_numpy_arrays_on_the_dsm_grid(data):
    r = geohaz.runout.run(config=data / CASE, duration=20, threads=1)
    gt = r["geotransform"]
    assert gt[1] == 2.5 and gt[5] == -2.5 and gt[2] == gt[4] == 0.0
    assert "UTM zone 54N" in r["crs_wkt"]
    maps = r["maps"]
    assert set(maps) == {"max_depth", "max_speed", "max_pressure", "deposit", "mobile_at_end", "arrival_time",
                         "max_momentum", "intensity"}
    for a in maps.values():
        assert a.shape == (200, 400) and a.dtype == np.float64
    cell = gt[1] * -gt[5]
    s = r["summary"]
    # The thickness maps integrate to the volumes of the summary (they are the same numbers).
    assert np.nansum(maps["deposit"]) * cell == pytest.approx(s["volumes_m3"]["deposit_raster"], rel=1e-12)
    assert np.nansum(maps["mobile_at_end"]) * cell == pytest.approx(s["volumes_m3"]["mobile_raster"], rel=1e-12)
    assert np.nansum(r["release_thickness"]) * cell == pytest.approx(s["volumes_m3"]["release_read"], rel=1e-12)
    assert np.nanmax(maps["max_speed"]) == s["max_speed_m_per_s"]
    assert np.nanmax(maps["max_pressure"]) == pytest.approx(1800.0 * s["max_speed_m_per_s"] ** 2, rel=1e-12)
    reached = maps["max_depth"] > 0
    # Intensity: every reached cell is medium (2) or strong (3) under the default depth-speed rule;
    # strong exactly where peak depth and peak speed both exceed 1.
    assert set(np.unique(maps["intensity"][reached])) <= {2.0, 3.0}
    strong = reached & (maps["max_depth"] > 1.0) & (maps["max_speed"] > 1.0)
    assert np.array_equal(maps["intensity"] == 3.0, strong)
    assert np.nanmax(maps["max_momentum"]) <= np.nanmax(maps["max_depth"]) * np.nanmax(maps["max_speed"]) + 1e-12
    assert np.all(np.isfinite(maps["arrival_time"][reached & (maps["max_speed"] > 0)]))
    assert np.all(maps["arrival_time"][np.isfinite(maps["arrival_time"])] <= 20.0 + 1e-9)
    # Particles: every field, volumes adding up to what is left in the domain.
    part = r["particles"]
    n = s["particles_left"]
    assert part["position"].shape == (n, 2) and part["speed"].shape == (n,)
    assert part["volume"].sum() == pytest.approx(s["volumes_m3"]["mobile"] + s["volumes_m3"]["deposited"], rel=1e-9)
    assert set(r["series"]) >= {"time_s", "front_travel_m", "max_speed_m_per_s"}
    assert r["series"]["time_s"][-1] == pytest.approx(20.0)


@pytest.mark.filterwarnings("ignore:the run ended at its duration")
def test_progress_callback_sees_every_nth_step_and_its_errors_stop_the_run(data):
    calls = []
    r = geohaz.runout.run(config=data / CASE, duration=10, threads=1, particles=False,
                          progress=calls.append, progress_every=10)
    steps = r["summary"]["steps"]
    assert calls[0]["phase"] == "started" and calls[-1]["phase"] == "finished"
    running = [c for c in calls if c["phase"] == "running"]
    assert len(running) == steps // 10
    assert [c["step"] for c in running] == list(range(10, steps + 1, 10))
    assert all(b["time"] > a["time"] for a, b in zip(running, running[1:]))
    assert calls[-1]["time"] == pytest.approx(10.0) and calls[-1]["duration"] == 10.0

    def stop(info):
        if info["step"] >= 5:
            raise KeyboardInterrupt("stopped from the callback")
    with pytest.raises(KeyboardInterrupt, match="stopped from the callback"):
        geohaz.runout.run(config=data / CASE, duration=10, threads=1, progress=stop)


def test_a_run_ended_at_its_duration_with_mass_moving_warns(data):
    with pytest.warns(RuntimeWarning, match="still moving"):
        r = geohaz.runout.run(config=data / CASE, duration=3, threads=1, particles=False)
    assert r["summary"]["unfinished"] and r["particles"] is None
    assert math.isclose(np.nansum(r["maps"]["mobile_at_end"]) * 6.25, r["summary"]["volumes_m3"]["mobile_raster"])


def test_help_config_is_the_apps():
    assert geohaz.runout.help_config() == app("debris-runout", "--help-config").stdout
