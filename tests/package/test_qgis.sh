#!/usr/bin/env bash
# ctest package_qgis (issue 37): the QGIS Processing provider (qgis/geohaz_provider) run headless by
# qgis_process on the small valley at a coarse particle spacing, and its maps checked against the
# same run made directly with the Python package (bit-identical: the same library code). Skipped,
# with a message, where QGIS is not installed (scripts/setup --qgis).
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
export XDG_RUNTIME_DIR=$tmp/xdg OMP_NUM_THREADS=1
mkdir -p "$HOME" "$XDG_RUNTIME_DIR" && chmod 700 "$XDG_RUNTIME_DIR"
"$qp" plugins enable geohaz_provider >"$tmp/enable.log" 2>&1 || { cat "$tmp/enable.log"; fail "plugins enable failed"; }
"$qp" list 2>/dev/null | grep -q "geohaz:debris_runout" || fail "geohaz:debris_runout not listed by qgis_process list"
# The inputs copied: QGIS writes GDAL .aux.xml statistics beside rasters it opens.
data=$tmp/data
mkdir -p "$data" && cp "$src"/data/runout/valley_small.tif "$src"/data/runout/valley_small_release.tif "$data"/
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
