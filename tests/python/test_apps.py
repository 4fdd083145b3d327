"""geohaz.dem: the app run from Python, its exit codes as exceptions (geohaz.sph runs in-process:
test_sph.py)."""
import pytest

import geohaz
from conftest import app, app_error


@pytest.mark.parametrize("module, name, case, bad", [
    (geohaz.dem, "dem-avalanche", "dem/biaxial_tension.toml", {"sample.porosity": 0.9}),
    (geohaz.dem, "dem-avalanche", "dem/biaxial_tension.toml", {"no.such_key": 1}),
])
def test_bad_input_raises_the_apps_message_and_writes_nothing(tmp_path, data, module, name, case, bad):
    sets = [f"{k}={v}" for k, v in bad.items()]
    expected = app_error(app(name, "--config", data / case, *sum((["--set", s] for s in sets), []),
                             "--out", tmp_path / "app"), name)
    with pytest.raises(geohaz.InputError) as e:
        module.run(data / case, set=bad, out=tmp_path / "py")
    assert str(e.value) == expected and e.value.exit_code == 2
    # file, key and value parsed back out of the message, as the in-process runout carries them
    key, value = next(iter(bad.items()))
    assert (e.value.file, e.value.key) == ("command line (--set)", key)
    assert e.value.value is None or float(e.value.value) == value  # the app writes numbers as it read them
    assert e.value.reason and expected.endswith(e.value.reason)
    assert not (tmp_path / "py").exists()


def test_a_dem_tension_test_returns_its_summary_and_curve(tmp_path, data):
    # The smallest bonded sample the app accepts (8 R_max a side), one tension test.
    small = {"sample.width": 0.015, "sample.height": 0.015, "sample.expansion_steps": 200,
             "sample.relax_steps": 500, "output.tessellation": False}
    r = geohaz.dem.run(data / "dem/biaxial_tension.toml", set=small, out=tmp_path / "t")
    t = r["summary"]["tests"][0]
    assert r["summary"]["test"] == "biaxial-tension" and t["peak_stress_Pa"] > 0
    curve = r["tables"]["curve_tension"]
    assert len(curve["axial_stress_Pa"]) >= 3
    # The peak is taken from the recorded points or between them: never below the highest one.
    assert 0.5 * t["peak_stress_Pa"] <= max(curve["axial_stress_Pa"]) <= t["peak_stress_Pa"] * (1 + 1e-9)
    assert (tmp_path / "t/summary.json").exists()
