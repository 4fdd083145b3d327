"""geohaz.sph: the sph-slope run in-process from Python against the app on the same case."""
import csv
import json

import numpy as np
import pytest

import geohaz
from conftest import app, app_error

# A 2D granular slope at 2 cm spacing (450 soil particles), 0.02 s geostatic + 0.02 s main phase:
# about a second. The strength reduction: ACADS 1(a) at 2 m spacing, three short trials.
SLOPE = ("sph/slope_2d_granular.toml",
         {"run.end_time": 0.02, "numerics.spacing": 0.02, "geostatic.duration": 0.02, "run.output_interval": 0.005})
SRM = ("sph/acads_1a_srm.toml",
       {"numerics.spacing": 2.0, "strength_reduction.trial_duration": 0.5, "strength_reduction.tolerance": 0.2})


def sets(overrides):
    return sum((["--set", f"{k}={v}"] for k, v in overrides.items()), [])


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array([[float(v) for v in r] for r in rows[1:]]).reshape(len(rows) - 1, len(rows[0]))


@pytest.mark.parametrize("case, overrides", [SLOPE, SRM], ids=["dynamic", "strength_reduction"])
def test_a_run_from_python_matches_the_app_and_writes_the_same_outputs(tmp_path, data, case, overrides):
    proc = app("sph-slope", "--config", data / case, *sets(overrides), "--threads", "1", "--quiet",
               "--out", tmp_path / "app")
    assert proc.returncode == 0, proc.stderr
    r = geohaz.sph.run(data / case, set=overrides, threads=1, out=tmp_path / "py")
    names = sorted(p.name for p in (tmp_path / "app").iterdir())
    assert sorted(p.name for p in (tmp_path / "py").iterdir()) == names
    a = json.loads((tmp_path / "app/summary.json").read_text())
    p = json.loads((tmp_path / "py/summary.json").read_text())
    s = dict(r["summary"])
    for d in (a, p, s):
        d.pop("wall_time_s")
    assert p == a and s == a  # the same run, bit for bit on one thread, and the same summary builder
    assert (tmp_path / "py/config.resolved.toml").read_text() == r["resolved_config"]
    # Every CSV: the same bytes as the app's, and the returned table holds its numbers (9 digits).
    csvs = [n for n in names if n.endswith(".csv")]
    assert sorted(r["tables"]) == sorted(n[:-4] for n in csvs)
    for n in csvs:
        assert (tmp_path / "py" / n).read_bytes() == (tmp_path / "app" / n).read_bytes(), n
        header, values = read_csv(tmp_path / "app" / n)
        table = r["tables"][n[:-4]]
        assert list(table) == header, n
        for k, column in enumerate(header):
            np.testing.assert_allclose(table[column], values[:, k], rtol=5e-9, atol=0, err_msg=f"{n}: {column}")


def test_the_particle_fields_are_the_final_state_of_the_summary(tmp_path, data):
    case, overrides = SLOPE
    r = geohaz.sph.run(data / case, set=overrides, threads=1)
    s, f = r["summary"], r["particles"]
    n = s["soil_particles"] + s["boundary_particles"]
    assert f["position"].shape == (n, 2) and f["stress"].shape == (n, 3, 3)
    soil = f["kind"] == 0
    assert soil.sum() == s["soil_particles"]
    # The summary's maxima are computed from these very arrays.
    assert np.linalg.norm(f["displacement"][soil], axis=1).max() == s["max_displacement_m"] > 0
    assert f["plastic_strain"].max() == s["max_plastic_strain"]
    assert np.all(f["material_id"][soil] == 0) and len(np.unique(f["id"])) == n
    assert np.allclose(f["stress"], np.transpose(f["stress"], (0, 2, 1)))  # symmetric Cauchy stress
    assert r["out"] is None and r["tables"]["series"]["time_s"][-1] == pytest.approx(s["end_time_s"], abs=0)


def test_the_pore_pressure_is_a_particle_field(data):
    # r_u = 0.25 on the example slope: every soil particle's u, the largest of which the summary reports
    # (at the series' rows: the last row is this state, the slope at rest, so within 1e-6 of it).
    r = geohaz.sph.run(data / "sph/slope_water_newmark.toml", threads=1,
                       set={"run.analysis": "dynamic", "earthquake.type": "none", "water.phreatic": [],
                            "water.ru": 0.25, "numerics.spacing": 2.0, "run.end_time": 0.02})
    s, f = r["summary"], r["particles"]
    soil = f["kind"] == 0
    assert f["pore_pressure"].shape == f["density"].shape
    assert s["water"]["source"] == "ru" and s["water"]["ru"] == 0.25
    assert f["pore_pressure"][soil].max() == pytest.approx(s["water"]["max_pore_pressure_Pa"], rel=1e-6)
    assert np.all(f["pore_pressure"][~soil] == 0)


@pytest.mark.parametrize("bad", [
    {"no.such_key": 1},                                   # unknown key
    {"run.end_time": -1.0},                               # out of range
    {"material[0].residual_cohesion": 1e3},              # a key of another model (read_config)
    {"output.structures": "pile_9"},                     # no such structure (validate)
])
def test_bad_input_raises_the_apps_message_and_writes_nothing(tmp_path, data, bad):
    case = data / SLOPE[0]
    expected = app_error(app("sph-slope", "--config", case, *sets(bad), "--out", tmp_path / "app"), "sph-slope")
    with pytest.raises(geohaz.InputError) as e:
        geohaz.sph.run(case, set=bad, out=tmp_path / "py")
    assert str(e.value) == expected and isinstance(e.value, ValueError)
    key = next(iter(bad))
    assert e.value.key == key.replace("[0]", "")  # the key as the message names it
    assert e.value.reason and expected.endswith(e.value.reason)
    assert not (tmp_path / "py").exists() and not (tmp_path / "app").exists()


def test_progress_is_called_with_increasing_time_through_the_phases(data):
    case, overrides = SLOPE
    events = []
    r = geohaz.sph.run(data / case, set=overrides, threads=1, progress=events.append, progress_every=5)
    phases = [e["phase"] for e in events]
    main = phases.index("started")
    assert set(phases[:main]) == {"geostatic"} and phases[-1] == "finished"
    assert set(phases[main + 1:-1]) == {"running"}
    for part in (events[:main], events[main:]):
        times = [e["time"] for e in part]
        steps = [e["step"] for e in part]
        assert times == sorted(times) and steps == sorted(steps) and times[-1] > times[0]
    assert events[main - 1]["time"] == pytest.approx(0.02) and events[main - 1]["end_time"] == 0.02
    steps, first = r["summary"]["steps"], events[main]["step"]  # the solver counts the geostatic steps too
    assert first == r["summary"]["geostatic"]["steps"] > 0
    assert len(phases) - main - 2 == len([k for k in range(first + 1, steps + 1) if k % 5 == 0])
    assert events[-1]["step"] == steps and events[-1]["time"] >= events[-1]["end_time"] - 1e-12


def test_a_failing_callback_stops_the_run(data):
    def stop(e):
        if e["phase"] == "running":
            raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        geohaz.sph.run(data / SLOPE[0], set=SLOPE[1], threads=1, progress=stop)


def test_help_config_is_the_apps():
    assert geohaz.sph.help_config() == app("sph-slope", "--help-config").stdout
