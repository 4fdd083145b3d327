#!/usr/bin/env bash
# ctest package_deb: build the Debian package with CPack, unpack it into a clean folder
# (dpkg-deb -x, as dpkg would install it under /), check its control fields, and run what it
# installed from outside the source tree: debris-runout --version, a run on its example data, and
# the Python module.
#   test_deb.sh <build dir> <version> <python3>
set -euo pipefail
build=$1
version=$2
python=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "test_deb: $*" >&2; exit 1; }
arch=$(dpkg --print-architecture)
(cd "$build" && cpack -G DEB -B "$tmp/cpack" >"$tmp/cpack.log" 2>&1) || { cat "$tmp/cpack.log"; fail "cpack failed"; }
deb=$tmp/cpack/geohaz_${version}_${arch}.deb
[ -f "$deb" ] || { ls "$tmp/cpack"; fail "no geohaz_${version}_${arch}.deb"; }
echo "test_deb: $(basename "$deb"), $(du -k "$deb" | cut -f1) kB"
depends=$(dpkg-deb -f "$deb" Depends)
echo "test_deb: Depends: $depends"
for p in libgdal libhdf5 libboost-program-options python3-numpy libgomp1; do
  [[ $depends == *"$p"* ]] || fail "Depends lacks $p"
done
root=$tmp/root
dpkg-deb -x "$deb" "$root"
for f in usr/bin/debris-runout usr/bin/sph-slope usr/bin/dem-avalanche usr/lib/libgeohaz_core.a \
         usr/include/geohaz/runout/run.hpp usr/lib/cmake/geohaz/geohazConfig.cmake \
         usr/lib/python3/dist-packages/geohaz/__init__.py usr/share/geohaz/data/runout/alr.toml \
         usr/share/geohaz/docs/python.md usr/share/bash-completion/completions/sph-slope; do
  [ -e "$root/$f" ] || fail "not in the package: $f"
done
cd "$tmp"  # outside the source tree
out=$("$root/usr/bin/debris-runout" --version)
[ "$out" = "debris-runout $version" ] || fail "debris-runout --version printed '$out'"
echo "test_deb: $out"
# The installed Python module, found the way Debian's python3 finds /usr/lib/python3/dist-packages.
PYTHONPATH=$root/usr/lib/python3/dist-packages GEOHAZ_BIN_DIR=$root/usr/bin "$python" - "$root" "$version" <<'PY'
import sys, pathlib
root, version = pathlib.Path(sys.argv[1]), sys.argv[2]
import geohaz
assert geohaz.__version__ == version, geohaz.__version__
assert pathlib.Path(geohaz.__file__).is_relative_to(root), geohaz.__file__
data = root / "usr/share/geohaz/data/runout"
try:
    geohaz.runout.run(data / "valley_small.tif", release=data / "valley_small_release.tif", n=1.0)
except geohaz.InputError as e:
    assert e.key == "model.n" and "[0.005, 0.5]" in str(e), str(e)
else:
    raise AssertionError("n = 1 was accepted")
r = geohaz.runout.run(config=data / "valley_small.toml", duration=5.0, particles=False)
assert r["maps"]["max_depth"].shape == (200, 400)
assert abs(r["summary"]["simulated_time_s"] - 5.0) < 1e-9
print("test_deb: import geohaz", geohaz.__version__, "from", geohaz.__file__, "and a 5 s run: ok")
PY
