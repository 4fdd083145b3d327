#!/usr/bin/env bash
# ctest package_qgis (issue 37): the QGIS Processing provider (qgis/geohaz_provider) run headless by
# qgis_process on the small valley at a coarse particle spacing: debris_runout (its maps against the
# same run made directly with the Python package, bit-identical: the same library code), ensemble
# (against geohaz.ensemble.run), calibrate (the comparison map against the best member's TP/FP/FN,
# best.toml against the best values) and slope_stability (FS before the rain against the
# infinite-slope formula per cell, the release volume against the failed cells, every map against
# the app run with the same keys written by hand); Cancel of debris_runout, ensemble and calibrate
# from QGIS's Python. Skipped, with a message, where QGIS is not installed (scripts/setup --qgis).
#   test_qgis.sh <source dir> <build dir> <python3>
set -euo pipefail
src=$1 build=$2 python=$3
qp=$(command -v qgis_process.bin || true)
[ -z "$qp" ] && [ -x /usr/lib/qgis/qgis_process.bin ] && qp=/usr/lib/qgis/qgis_process.bin
if [ -z "$qp" ]; then
  echo "test_qgis: SKIPPED: qgis_process.bin not found (Debian qgis + python3-qgis: scripts/setup --qgis)"
  exit 77
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "test_qgis: $*" >&2; exit 1; }
# A profile of its own (HOME), no display, the plugin from the source tree, geohaz from the build.
export HOME=$tmp/home QT_QPA_PLATFORM=offscreen QGIS_PLUGINPATH=$src/qgis PYTHONPATH=$build/python
export XDG_RUNTIME_DIR=$tmp/xdg OMP_NUM_THREADS=1 PYTHONDONTWRITEBYTECODE=1
export GEOHAZ_BIN_DIR=$build/apps/slope-stability:$build/apps/geohaz-report
mkdir -p "$HOME" "$XDG_RUNTIME_DIR" && chmod 700 "$XDG_RUNTIME_DIR"
"$qp" plugins enable geohaz_provider >"$tmp/enable.log" 2>&1 || { cat "$tmp/enable.log"; fail "plugins enable failed"; }
"$qp" list 2>/dev/null >"$tmp/list.txt"
for alg in debris_runout ensemble calibrate slope_stability report; do
  grep -q "geohaz:$alg" "$tmp/list.txt" || fail "geohaz:$alg not listed by qgis_process list"
done
# The inputs copied: QGIS writes GDAL .aux.xml statistics beside rasters it opens.
data=$tmp/data
mkdir -p "$data" && cp "$src"/data/runout/valley_small.tif "$src"/data/runout/valley_small_release.tif \
  "$src"/data/runout/valley_small.toml "$src"/data/runout/valley_small_event_max_depth.tif \
  "$src"/data/runout/valley_small_thalweg.geojson "$data"/
"$qp" run geohaz:debris_runout -- DSM="$data/valley_small.tif" RELEASE_RASTER="$data/valley_small_release.tif" \
  FRICTION=0 N=0.06 ICR=0.15 D0=10 H0=0.5 DURATION=30 OUTPUT="$tmp/out" >"$tmp/run.log" 2>&1 || {
  cat "$tmp/run.log"; fail "qgis_process run failed"; }
grep -q "MAPS" "$tmp/run.log" || { cat "$tmp/run.log"; fail "no MAPS output in the result"; }
"$python" - "$tmp/out" "$data" <<'PY'
import sys, warnings
import numpy as np
import geohaz
out, data = sys.argv[1], sys.argv[2]
back = geohaz.read_run(out)
assert back["summary"]["simulated_time_s"] <= 30.0 + 1e-9, back["summary"]["simulated_time_s"]
assert np.nanmax(back["maps"]["max_depth"]) > 0.0
with warnings.catch_warnings():
    warnings.simplefilter("ignore", RuntimeWarning)
    r = geohaz.runout.run(f"{data}/valley_small.tif", release=f"{data}/valley_small_release.tif",
                          friction="manning", n=0.06, icr=0.15, d0=10.0, h0=0.5, duration=30.0, particles=False)
for name in ("max_depth", "max_speed", "deposit"):
    np.testing.assert_array_equal(back["maps"][name], r["maps"][name].astype(np.float32).astype(float), err_msg=name)
import os
assert os.path.isfile(f"{out}/max_speed.qml"), "no style beside max_speed.tif"
print("test_qgis: qgis_process geohaz:debris_runout = geohaz.runout.run, maps identical:",
      back["summary"]["runout_length_along_path_m"], "m run-out")
PY

# Cancel: the algorithm run from QGIS's Python with a feedback that cancels at the first progress
# report stops the run and writes no maps.
"$python" - "$src/qgis" "$data" "$tmp/canceled" <<'PY'
import sys
plugins, data, out = sys.argv[1:4]
sys.path.insert(0, plugins)
from qgis.core import QgsApplication, QgsProcessingContext, QgsProcessingFeedback
app = QgsApplication([], False)
app.initQgis()
from geohaz_provider.algorithms import DebrisRunoutAlgorithm


class CancelAtFirstProgress(QgsProcessingFeedback):
    def __init__(self):
        super().__init__()
        self.progress_seen = []
        self.progressChanged.connect(self._cancel)

    def _cancel(self, p):
        self.progress_seen.append(p)
        self.cancel()


alg = DebrisRunoutAlgorithm()
alg.initAlgorithm()
context, feedback = QgsProcessingContext(), CancelAtFirstProgress()
params = {"DSM": f"{data}/valley_small.tif", "RELEASE_RASTER": f"{data}/valley_small_release.tif", "FRICTION": 0,
          "N": 0.06, "ICR": 0.15, "D0": 10.0, "H0": 0.5, "DURATION": 600.0, "OUTPUT": out}
ok = alg.prepare(params, context, feedback)
assert ok, "prepare failed"
result = alg.runPrepared(params, context, feedback)
import os
assert feedback.progress_seen and feedback.isCanceled(), feedback.progress_seen
assert result == {}, result
assert not os.path.exists(f"{out}/max_depth.tif"), "a canceled run wrote maps"
print(f"test_qgis: canceled at {feedback.progress_seen[0]:.1f} % of a 600 s run: no maps written")
app.exitQgis()
PY

# --- geohaz:ensemble: three coarse members, the maps as geohaz.ensemble.run makes them ---------
cat >"$data/ens.toml" <<TOML
[ensemble]
base = "$data/valley_small.toml"
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
TOML
"$qp" run geohaz:ensemble -- CONFIG="$data/ens.toml" OUTPUT="$tmp/ens" >"$tmp/ens.log" 2>&1 || {
  cat "$tmp/ens.log"; fail "qgis_process geohaz:ensemble failed"; }
"$python" - "$tmp/ens" "$data/ens.toml" <<'PY'
import sys
import numpy as np
import geohaz
out, cfg = sys.argv[1:3]
back = geohaz.read_run(out)
r = geohaz.ensemble.run(cfg)
assert back["summary"]["succeeded"] == r["summary"]["succeeded"] == 3
for name, m in r["maps"].items():
    np.testing.assert_array_equal(back["maps"][name], m, err_msg=name)
p = back["maps"]["prob_max_depth_gt_0.5m"]
k = 3 * p[np.isfinite(p)]  # k of 3 members (Float32 GeoTIFF)
np.testing.assert_allclose(k, np.round(k), atol=1e-6)
assert set(np.unique(np.round(k))) <= {0, 1, 2, 3} and k.max() == 3.0
print(f"test_qgis: qgis_process geohaz:ensemble = geohaz.ensemble.run, {len(r['maps'])} maps identical")
PY

# --- geohaz:calibrate: n and i_cr of the small valley against its event footprint, few members ---
"$qp" run geohaz:calibrate -- DSM="$data/valley_small.tif" RELEASE_RASTER="$data/valley_small_release.tif" \
  OBSERVED_RASTER="$data/valley_small_event_max_depth.tif" FOOTPRINT_THRESHOLD=0.1 \
  THALWEG="$data/valley_small_thalweg.geojson" FRICTION=0 N_RANGE=0.03,0.12 ICR_RANGE=0.08,0.3 \
  D0=10 H0=0.5 DURATION=90 GLOBAL_MEMBERS=4 MORRIS_TRAJECTORIES=0 LOCAL_STARTS=1 LOCAL_EVALUATIONS=4 \
  OUTPUT="$tmp/cal" >"$tmp/cal.log" 2>&1 || { cat "$tmp/cal.log"; fail "qgis_process geohaz:calibrate failed"; }
"$python" - "$tmp/cal" "$tmp/cal.log" <<'PY'
import re, sys, tomllib
import numpy as np
import geohaz
out, log = sys.argv[1], open(sys.argv[2]).read()
r = geohaz.read_run(out)
s = r["summary"]
best = s["best"]
# Bounds and the base case as the inputs said.
assert [(p["key"], p["min"], p["max"], p["scale"]) for p in s["parameters"]] == \
    [("model.n", 0.03, 0.12, "log"), ("model.icr", 0.08, 0.3, "linear")], s["parameters"]
members = r["tables"]["members"]
assert 4 <= len(members["member"]) <= 8, len(members["member"])
# The best member has the lowest score of members.csv, and its values are in best.toml.
ok = members["status"] == "ok"
assert best["misfit"]["score"] == np.min(members["score"][ok]) or \
    abs(best["misfit"]["score"] - np.min(members["score"][ok])) < 1e-9 * best["misfit"]["score"]
fitted = tomllib.loads(open(f"{out}/best.toml").read())["model"]
assert fitted["n"] == best["parameters"]["model.n"] and fitted["icr"] == best["parameters"]["model.icr"]
assert fitted["d0"] == 10.0 and 0.03 <= fitted["n"] <= 0.12 and 0.08 <= fitted["icr"] <= 0.3
# The comparison map (loaded in QGIS) holds the best member's TP, FP and FN areas, and its Tversky
# index T = TP / (TP + FP/2 + FN/2) is the summary's.
cell = abs(r["geotransform"][1] * r["geotransform"][5])
area = {c: np.count_nonzero(r["maps"]["comparison"] == c) * cell for c in (1, 2, 3)}
for c, key in ((1, "tp_m2"), (2, "fp_m2"), (3, "fn_m2")):
    assert abs(area[c] - best["misfit"][key]) <= 1e-9 * max(1.0, best["misfit"][key]), (key, area[c], best["misfit"])
t = area[1] / (area[1] + 0.5 * area[2] + 0.5 * area[3])
assert abs(t - best["misfit"]["tversky"]) < 1e-12, (t, best["misfit"]["tversky"])
assert area[1] > 0 and 0.0 < t <= 1.0
# The algorithm's outputs: SCORE and BEST as in the summary.
score = float(re.search(r"SCORE:\s*([0-9.eE+-]+)", log).group(1))
assert abs(score - best["misfit"]["score"]) < 1e-6 * max(1.0, score), (score, best["misfit"]["score"])
assert f"model.n={best['parameters']['model.n']:.6g}" in log, log
print(f"test_qgis: qgis_process geohaz:calibrate: {len(members['member'])} members, best n = {fitted['n']:.4g}, "
      f"i_cr = {fitted['icr']:.4g}, T = {t:.4f} from the comparison map = summary")
PY

# --- geohaz:slope_stability: a storm on the valley's flanks ---------------------------------------
# c' = 6 kPa, phi' = 36 deg, 1.2 m of soil on slopes 20-50 deg, the water table at the contact; six
# hours of 20 mm/h (5.556e-6 m/s), FS every 30 min.
stab=(SOIL_DEPTH=1.2 MIN_SLOPE=20 MAX_SLOPE=50 COHESION=6000 FRICTION_ANGLE=36 UNIT_WEIGHT_MOIST=18000
  UNIT_WEIGHT_SATURATED=20000 CONDUCTIVITY=1e-5 DIFFUSIVITY=5e-5 WATER_TABLE_DEPTH=1.2 RAIN_STEP=3600
  TIME_STEP=1800 "RAIN_INTENSITY=5.556e-6,5.556e-6,5.556e-6,5.556e-6,5.556e-6,5.556e-6")
"$qp" run geohaz:slope_stability -- DSM="$data/valley_small.tif" "${stab[@]}" OUTPUT="$tmp/stab" \
  >"$tmp/stab.log" 2>&1 || { cat "$tmp/stab.log"; fail "qgis_process geohaz:slope_stability failed"; }
cat >"$tmp/stab.toml" <<'TOML'
[soil]
depth = 1.2
min_slope = 20.0
max_slope = 50.0
cohesion = 6000.0
friction_angle = 36.0
unit_weight_moist = 18000.0
unit_weight_saturated = 20000.0
[hydrology]
conductivity = 1e-5
diffusivity = 5e-5
water_table_depth = 1.2
[rain]
step = 3600.0
intensity = [5.556e-6, 5.556e-6, 5.556e-6, 5.556e-6, 5.556e-6, 5.556e-6]
[run]
time_step = 1800.0
TOML
"$build/apps/slope-stability/slope-stability" "$data/valley_small.tif" --config "$tmp/stab.toml" --quiet \
  --out "$tmp/stab-app" || fail "slope-stability (the app, for comparison) failed"
"$python" - "$tmp/stab" "$tmp/stab-app" "$tmp/stab.log" <<'PY'
import math, re, sys
import numpy as np
import geohaz
out, app, log = sys.argv[1], sys.argv[2], open(sys.argv[3]).read()
r, a = geohaz.read_run(out), geohaz.read_run(app)
# Every map equals the app's run with the same keys written by hand (the inputs reached their keys).
for name in ("fs_min", "failure_time", "max_pressure_head", "slope"):
    np.testing.assert_array_equal(r["maps"][name], a["maps"][name], err_msg=name)
# Before the rain the water table is at the failure plane (d = Z): no pressure head on it, the
# column moist, FS = tan(phi')/tan(delta) + c'/(gamma_m Z sin(delta) cos(delta)), capped at 10.
fs0 = geohaz.read_raster(f"{out}/fs/fs_t0000000s.tif")["values"]
delta = np.radians(r["maps"]["slope"])
cells = np.isfinite(fs0)
assert cells.sum() > 100, cells.sum()
d = delta[cells]
expected = np.minimum(math.tan(math.radians(36.0)) / np.tan(d) + 6000.0 / (18000.0 * 1.2 * np.sin(d) * np.cos(d)), 10.0)
np.testing.assert_allclose(fs0[cells], expected, rtol=2e-6)  # Float32 maps
assert np.all((r["maps"]["slope"][cells] >= 20.0 - 1e-4) & (r["maps"]["slope"][cells] <= 50.0 + 1e-4))
# The rain fails cells: each failed cell has a failure time within the run, FS_min < 1 there, and
# the release is Z x cell area per failed cell.
s = r["summary"]
ft = r["maps"]["failure_time"]
failed = np.isfinite(ft)
assert s["cells"]["failed"] == failed.sum() > 0, (s["cells"], failed.sum())
assert np.all((ft[failed] > 0) & (ft[failed] <= 6 * 3600.0))  # none before the rain: FS0 > 1
assert s["cells"]["unstable_before_rain"] == 0 and np.all(fs0[cells] > 1.0)
assert np.all(r["maps"]["fs_min"][failed] < 1.0 + 1e-6)
cell = s["cells"]["cell_area_m2"]
assert abs(s["release"]["volume_m3"] - failed.sum() * 1.2 * cell) <= 1e-9 * s["release"]["volume_m3"]
assert s["rain"]["peak_intensity_m_per_s"] == 5.556e-6  # the key rule (docs/python.md)
vol = float(re.search(r"RELEASE_VOLUME:\s*([0-9.eE+-]+)", log).group(1))
assert abs(vol - s["release"]["volume_m3"]) <= 1e-6 * vol, (vol, s["release"]["volume_m3"])
print(f"test_qgis: qgis_process geohaz:slope_stability: FS before the rain = infinite-slope formula on "
      f"{cells.sum()} cells; {failed.sum()} cells failed, release {s['release']['volume_m3']:.1f} m3 = failed x Z x A")
PY

# --- Cancel of ensemble and calibrate from QGIS's Python: stops in the second member --------------
"$python" - "$src/qgis" "$data" "$tmp" <<'PY'
import os, sys
plugins, data, tmp = sys.argv[1:4]
sys.path.insert(0, plugins)
from qgis.core import QgsApplication, QgsProcessingContext, QgsProcessingFeedback
app = QgsApplication([], False)
app.initQgis()
from geohaz_provider.algorithms import EnsembleAlgorithm
from geohaz_provider.calibration import CalibrateAlgorithm


class CancelInSecondMember(QgsProcessingFeedback):
    """Cancels once the progress passes one member's share (the bar follows members done)."""

    def __init__(self, members):
        super().__init__()
        self.seen = []
        self.share = 100.0 / members
        self.progressChanged.connect(self._progress)

    def _progress(self, p):
        self.seen.append(p)
        if p > 1.2 * self.share:
            self.cancel()


def run(alg, params, members):
    alg.initAlgorithm()
    context, feedback = QgsProcessingContext(), CancelInSecondMember(members)
    assert alg.prepare(params, context, feedback), "prepare failed"
    return alg.runPrepared(params, context, feedback), feedback


out = f"{tmp}/ens-canceled"
result, fb = run(EnsembleAlgorithm(), {"CONFIG": f"{data}/ens.toml", "OUTPUT": out}, 3)
assert result == {} and fb.isCanceled(), result
assert fb.seen == sorted(fb.seen), "progress went backwards"
assert os.listdir(f"{out}/members") == ["000000"], os.listdir(f"{out}/members")  # member 1 left nothing
assert not [f for f in os.listdir(out) if f.endswith(".tif")], os.listdir(out)
print(f"test_qgis: geohaz:ensemble canceled at {fb.seen[-1]:.0f} %: member 0 kept, no maps written")

out = f"{tmp}/cal-canceled"
params = {"DSM": f"{data}/valley_small.tif", "RELEASE_RASTER": f"{data}/valley_small_release.tif",
          "OBSERVED_RASTER": f"{data}/valley_small_event_max_depth.tif", "FOOTPRINT_THRESHOLD": 0.1,
          "THALWEG": f"{data}/valley_small_thalweg.geojson", "FRICTION": 0, "N_RANGE": "0.03,0.12",
          "ICR_RANGE": "0.08,0.3", "D0": 10.0, "H0": 0.5, "DURATION": 90.0, "GLOBAL_MEMBERS": 4,
          "MORRIS_TRAJECTORIES": 0, "LOCAL_STARTS": 1, "LOCAL_EVALUATIONS": 4, "OUTPUT": out}
result, fb = run(CalibrateAlgorithm(), params, 8)
assert result == {} and fb.isCanceled(), result
assert os.listdir(f"{out}/members") == ["000000"], os.listdir(f"{out}/members")
assert not os.path.exists(f"{out}/best.toml") and not os.path.exists(f"{out}/comparison.tif")
print(f"test_qgis: geohaz:calibrate canceled at {fb.seen[-1]:.0f} %: member 0 kept, no best.toml")
app.exitQgis()
PY
