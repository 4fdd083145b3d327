#!/usr/bin/env bash
# The Python package as a user installs it (issue 37): a fresh venv (with Debian's NumPy visible),
# `pip install --no-build-isolation <source>` (setup.py builds the module with CMake for the venv's
# interpreter), the pytest files run with that venv's python from outside the source tree, and a
# wheel built with `python3 -m build --wheel --no-isolation` that holds the module.
# Arguments: source dir, build dir, python3. The CMake build folder of the pip build is kept in
# <build>-pip, beside the build folder rather than in it: at the same depth below the source tree,
# ccache (base_dir) sees the same relative paths as in the build folder and reuses its objects, and
# a second run only relinks.
set -euo pipefail
src=$1 build=$2 python=$3
work=$build/pip-test
rm -rf "$work/venv" "$work/dist" "$work/run"
mkdir -p "$work/run"
"$python" -m venv --system-site-packages "$work/venv"
py=$work/venv/bin/python
export GEOHAZ_CMAKE_BUILD_DIR=$build-pip
unset PYTHONPATH
"$py" -m pip install --no-build-isolation --no-deps -q "$src" >"$work/pip.log" 2>&1 || {
  tail -40 "$work/pip.log"
  echo "venv install: pip install failed (log $work/pip.log)" >&2
  exit 1
}
# Imported from the venv, not from the build tree or the source tree.
cd "$work/run"
where=$("$py" -c 'import geohaz, os; print(os.path.dirname(geohaz.__file__))')
case $where in
  "$work/venv/"*) ;;
  *) echo "venv install: geohaz imported from $where, not from the venv" >&2; exit 1 ;;
esac
version=$("$py" -c 'import geohaz; print(geohaz.__version__)')
pipversion=$("$py" -m pip show geohaz | sed -n 's/^Version: //p')
[ "$version" = "$pipversion" ] || { echo "venv install: module $version, pip metadata $pipversion" >&2; exit 1; }
"$py" -m pytest -q -p no:cacheprovider "$src"/tests/python/test_*.py

# The wheel (Debian's python3-build); skipped with a message where it is missing.
if "$python" -c 'import build' 2>/dev/null; then
  "$py" -m build --wheel --no-isolation --outdir "$work/dist" "$src" >"$work/wheel.log" 2>&1 || {
    tail -40 "$work/wheel.log"
    echo "venv install: python3 -m build --wheel failed (log $work/wheel.log)" >&2
    exit 1
  }
  wheel=$(ls "$work"/dist/geohaz-"$version"-cp3*-linux_*.whl)
  "$py" -m zipfile -l "$wheel" | grep -q 'geohaz/_geohaz\.cpython-.*\.so' || {
    echo "venv install: $wheel holds no compiled module" >&2
    exit 1
  }
  echo "venv install: wheel $(basename "$wheel")"
else
  echo "venv install: python3-build not installed, wheel not checked (scripts/setup installs it)"
fi
