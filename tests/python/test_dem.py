"""geohaz.dem: dem-avalanche run in-process (libs/dem/run.hpp), checked against the app."""
import json
import warnings

import numpy as np
import pytest

import geohaz
from geohaz._keys import canonical_keys
from conftest import app, app_error

# The smallest bonded sample the app accepts (8 R_max a side), one tension test: ~1 s.
TINY_LAB = {"sample.width": 0.015, "sample.height": 0.015, "sample.expansion_steps": 200,
            "sample.relax_steps": 500, "output.tessellation": False}
# A coarse rock mass (discs of 1.2-2 m) settling 0.2 s and running 2 s: ~1 s.
TINY_AVALANCHE = {"sample.r_min": 1.2, "sample.r_max": 2.0, "avalanche.settle_time": 0.2,
                  "avalanche.runout_time": 2.0, "output.snapshot_every": 0}


def sets(d):
    return sum((["--set", f"{k}={geohaz._overrides.toml_value(v)}"] for k, v in d.items()), [])


def test_a_lab_run_gives_the_apps_summary_tables_and_files(tmp_path, data):
    case = data / "dem/biaxial_tension.toml"
    proc = app("dem-avalanche", "--config", case, *sets(TINY_LAB), "--threads", "1", "--quiet",
               "--out", tmp_path / "app")
    assert proc.returncode == 0, proc.stderr
    r = geohaz.dem.run(case, set=TINY_LAB, out=tmp_path / "py", threads=1)
    # One summary builder: the dict is the app's summary.json, number for number.
    assert r["summary"] == canonical_keys(json.loads((tmp_path / "app/summary.json").read_text()))  # key rule: docs/python.md
    assert (tmp_path / "py/summary.json").read_text() == (tmp_path / "app/summary.json").read_text()
    # The same files, the same tables (also as arrays).
    app_files = sorted(p.name for p in (tmp_path / "app").iterdir() if p.suffix != ".h5")
    assert sorted(p.name for p in (tmp_path / "py").iterdir() if p.suffix != ".h5") == app_files
    for name in app_files:
        if name.endswith((".csv", ".toml")):
            assert (tmp_path / "py" / name).read_text() == (tmp_path / "app" / name).read_text(), name
    assert sorted(r["tables"]) == ["ae_tension", "curve_tension"]
    curve = r["tables"]["curve_tension"]
    rows = (tmp_path / "app/curve_tension.csv").read_text().splitlines()
    assert len(curve["axial_stress_Pa"]) == len(rows) - 1
    assert curve["axial_stress_Pa"][-1] == float(rows[-1].split(",")[4])
    t = r["summary"]["tests"][0]
    assert 0.5 * t["peak_stress_Pa"] <= max(curve["axial_stress_Pa"]) <= t["peak_stress_Pa"] * (1 + 1e-9)
    # The final discs: one row per disc of the sample.
    discs = r["discs"]["tension"]
    n = r["summary"]["sample"]["discs"]
    assert discs["position"].shape == (n, 2) and discs["velocity"].shape == (n, 2)
    assert discs["radius"].shape == (n,) and np.all(discs["radius"] > 0)
    assert sorted(discs["id"]) == list(range(n))


def test_an_avalanche_without_out_writes_nothing_and_returns_the_final_discs(tmp_path, data, monkeypatch):
    case = data / "dem/avalanche.toml"
    proc = app("dem-avalanche", "--config", case, *sets(TINY_AVALANCHE), "--threads", "1", "--quiet",
               "--out", tmp_path / "app")
    assert proc.returncode == 0, proc.stderr
    monkeypatch.chdir(tmp_path)
    with pytest.warns(RuntimeWarning, match="still moving"):  # 2 s: the mass is on its way
        r = geohaz.dem.run(case, set=TINY_AVALANCHE, threads=1)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["app"]
    s = r["summary"]
    assert s == canonical_keys(json.loads((tmp_path / "app/summary.json").read_text()))
    assert r["out"] is None and sorted(r["tables"]) == ["ae", "deposit", "fragments", "runout"]
    d = r["discs"]["avalanche"]
    assert d["position"].shape == (s["discs"], 2)
    # Fragment ids label the bonded clusters: as many as the summary counts, the largest as large.
    ids, counts = np.unique(d["fragment"], return_counts=True)
    assert len(ids) == s["fragments_final"] and counts.max() == s["largest_fragment_discs"]
    assert r["tables"]["fragments"]["discs"].sum() == s["discs"]


def test_progress_callback_sees_every_test_from_start_to_finish(data):
    seen = []
    r = geohaz.dem.run(data / "dem/biaxial_tension.toml", set=TINY_LAB, threads=1, progress=seen.append)
    phases = [p["phase"] for p in seen]
    assert phases[0] == "started" and phases[-1] == "finished" and "loading" in phases
    assert all(p["test"] == "tension" for p in seen)
    times = [p["time"] for p in seen[1:]]
    assert times == sorted(times) and times[-1] > 0
    assert seen[-1]["step"] > 0 and seen[-1]["discs"] == r["summary"]["sample"]["discs"]
    # every second record only: about half as many calls
    fewer = []
    geohaz.dem.run(data / "dem/biaxial_tension.toml", set=TINY_LAB, threads=1, progress=fewer.append,
                   progress_every=2)
    assert 2 < len(fewer) < len(seen)


@pytest.mark.parametrize("bad, key", [
    ({"no.such_key": 1}, "no.such_key"),
    ({"sample.porosity": 0.9}, "sample.porosity"),
    ({"avalanche.terrain_z": [0.0, 200.0, 200.0]}, "avalanche.terrain_x"),
])
def test_bad_input_raises_the_apps_message_naming_the_key_and_writes_nothing(tmp_path, data, bad, key):
    case = data / ("dem/avalanche.toml" if "avalanche.terrain_z" in bad else "dem/biaxial_tension.toml")
    args = sets(bad)
    expected = app_error(app("dem-avalanche", "--config", case, *args, "--out", tmp_path / "app"), "dem-avalanche")
    called = []
    with pytest.raises(geohaz.InputError) as e:
        geohaz.dem.run(case, set=bad, out=tmp_path / "py", progress=called.append)
    assert str(e.value) == expected and isinstance(e.value, ValueError)
    assert e.value.key == key and key in str(e.value)
    assert not (tmp_path / "py").exists() and not (tmp_path / "app").exists() and not called


def test_help_config_is_the_apps():
    proc = app("dem-avalanche", "--help-config")
    assert proc.returncode == 0
    assert geohaz.dem.help_config() == proc.stdout
