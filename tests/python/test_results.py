"""geohaz.read_run: an output folder read back equals the run's own arrays; one naming rule for keys."""
import json
import warnings

import numpy as np
import pytest

import geohaz


@pytest.fixture(scope="module")
def small_run(tmp_path_factory):
    """The small valley for 20 s (a few seconds of wall time), in memory and written to a folder."""
    from conftest import SOURCE
    out = tmp_path_factory.mktemp("run") / "out"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # unfinished after 20 s, on purpose
        r = geohaz.runout.run(config=SOURCE / "data/runout/valley_small.toml", set={"run.duration": 20.0},
                              out=out, threads=1, particles=False)
    return r, out


def test_read_run_gives_back_the_maps_written_to_disk(small_run):
    r, out = small_run
    back = geohaz.read_run(out)
    # Every GeoTIFF of the folder, and the run's maps among them. The files are Float32
    # (write_geotiff), so the in-memory float64 maps come back rounded to float32, NaN where NaN.
    assert set(r["maps"]) <= set(back["maps"])
    assert {p.stem for p in out.glob("*.tif")} == set(back["maps"])
    for name, mem in r["maps"].items():
        np.testing.assert_array_equal(back["maps"][name], mem.astype(np.float32).astype(np.float64), err_msg=name)
    assert back["units"]["maps"]["max_speed"] == "m/s"
    assert back["units"]["maps"]["max_pressure"] == "Pa"
    assert back["geotransform"] == pytest.approx(r["geotransform"])
    assert back["crs_wkt"] == r["crs_wkt"]
    # The series: series.csv is written with 10 significant digits.
    for col, mem in r["series"].items():
        np.testing.assert_allclose(back["series"][col], mem, rtol=1e-9, atol=1e-9, err_msg=col)
    assert back["units"]["tables"]["series"]["max_speed_m_per_s"] == "m/s"
    assert back["units"]["tables"]["series"]["time_s"] == "s"
    assert back["summary"]["runout_length_along_path_m"] == r["summary"]["runout_length_along_path_m"]
    assert "[model]" in back["resolved_config"]


def test_summary_keys_follow_one_rule_and_old_names_still_answer(small_run, tmp_path):
    r, out = small_run
    on_disk = json.loads((out / "summary.json").read_text())
    # The app writes the rule (issue #37): no compound unit without _per_ in its files.
    assert "max_speed_m_per_s" in on_disk and "max_speed_m_s" not in on_disk
    assert "max_speed_m_per_s" in on_disk["mobile_at_end"]
    series_header = (out / "series.csv").read_text().splitlines()[0].split(",")
    assert "mean_speed_m_per_s" in series_header and "max_speed_m_s" not in series_header
    assert [k for k in series_header if geohaz.results.canonical(k) != k] == []
    s = geohaz.read_run(out)["summary"]
    assert "max_speed_m_per_s" in r["summary"] and s["max_speed_m_per_s"] == on_disk["max_speed_m_per_s"]
    assert "mean_speed_m_per_s" in r["series"]
    # A folder written before the rename: read under the new names, the old one readable for a release.
    old = tmp_path / "old"
    old.mkdir()
    text = (out / "summary.json").read_text().replace("_m_per_s", "_m_s")
    (old / "summary.json").write_text(text)
    s_old = geohaz.read_run(old)["summary"]
    assert s_old["max_speed_m_per_s"] == on_disk["max_speed_m_per_s"]
    assert "max_speed_m_s" not in list(s_old)  # one spelling in the keys ...
    with pytest.warns(DeprecationWarning, match="max_speed_m_per_s"):
        assert s_old["max_speed_m_s"] == s_old["max_speed_m_per_s"]  # ... the old one readable for a release
    assert geohaz.results.canonical("x_m3_s") == "x_m3_per_s"
    assert geohaz.results.canonical("earthquake_acceleration_m_per_s2") == "earthquake_acceleration_m_per_s2"


def test_read_run_of_a_missing_folder_raises(tmp_path):
    with pytest.raises(FileNotFoundError):
        geohaz.read_run(tmp_path / "nothing")


def test_report_write_gives_the_page_of_the_app(small_run, tmp_path):
    """geohaz.report.write is geohaz-report's library: the same page from the same folder, with the
    run's run-out as the summary gives it; a folder without a run raises InputError, nothing written."""
    import shutil
    import subprocess
    from conftest import BIN
    r, out = small_run
    a, b = tmp_path / "a", tmp_path / "b"
    shutil.copytree(out, a / "run")
    shutil.copytree(out, b / "run")
    got = geohaz.report.write(a, title="t")
    assert got == {"html": str(a / "report.html"), "pdf": None}
    proc = subprocess.run([str(BIN / "geohaz-report" / "geohaz-report"), str(b), "--title", "t"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    page_a = (a / "report.html").read_text()
    page_b = (b / "report.html").read_text()
    assert page_a.replace(str(a), "") == page_b.replace(str(b), "")
    runout = json.loads((out / "summary.json").read_text())["runout_length_along_path_m"]
    assert f"{runout:.4g}".rstrip("0").rstrip(".")[:3] in page_a
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(geohaz.InputError):
        geohaz.report.write(empty)
    assert list(empty.iterdir()) == []
