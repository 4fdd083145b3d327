"""geohaz.sph: the app run from Python, its exit codes as exceptions (geohaz.dem: test_dem.py)."""
import pytest

import geohaz
from conftest import app, app_error


@pytest.mark.parametrize("module, name, case, bad", [
    (geohaz.sph, "sph-slope", "sph/biaxial.toml", {"run.end_time": -1.0}),
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

