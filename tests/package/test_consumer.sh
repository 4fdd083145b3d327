#!/usr/bin/env bash
# ctest package_consumer: install the build into a temporary prefix, check what is there (headers,
# libraries, CMake package, data, docs with working links, man pages, completion), then build and run
# tests/package/consumer against it with find_package(geohaz).
#   test_consumer.sh <build dir> <consumer source dir>
set -euo pipefail
build=$1
consumer=$2
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
prefix=$tmp/prefix
cmake --install "$build" --prefix "$prefix" >"$tmp/install.log"
fail() { echo "test_consumer: $*" >&2; exit 1; }
for f in include/geohaz/core/config.hpp include/geohaz/runout/run.hpp include/geohaz/sph/run.hpp \
         include/geohaz/dem/experiments.hpp include/geohaz/report/report.hpp lib/cmake/geohaz/geohazConfig.cmake \
         lib/cmake/geohaz/geohazConfigVersion.cmake lib/cmake/geohaz/geohazTargets.cmake \
         bin/debris-runout bin/sph-slope bin/dem-avalanche bin/geohaz-report \
         share/geohaz/README.md share/geohaz/docs/getting-started.md share/geohaz/data/runout/valley_small.tif \
         share/bash-completion/completions/debris-runout; do
  [ -e "$prefix/$f" ] || fail "not installed: $f"
done
ls "$prefix"/lib/libgeohaz_{core,sph,runout,dem,report}.* >/dev/null || fail "libraries not installed"
if [ -e "$build/man/debris-runout.1" ]; then
  # Installed gzipped (Debian policy 12.3), with SEE ALSO naming this prefix's data folder.
  page="$prefix/share/man/man1/debris-runout.1.gz"
  [ -s "$page" ] || fail "man page not installed (gzipped)"
  zgrep -q "model.friction" "$page" || fail "man page lacks the config keys"
  zgrep -q "$prefix/share/geohaz" "$page" || fail "man page SEE ALSO does not name $prefix/share/geohaz"
fi
python3 "$here/check_links.py" "$prefix/share/geohaz"
# The CMake package from a project that knows nothing of the source tree.
cmake -S "$consumer" -B "$tmp/consumer-build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
  >"$tmp/configure.log" 2>&1 || { cat "$tmp/configure.log"; fail "consumer configure failed"; }
cmake --build "$tmp/consumer-build" -j 2 >"$tmp/build.log" 2>&1 || { cat "$tmp/build.log"; fail "consumer build failed"; }
(cd "$tmp" && "$tmp/consumer-build/consumer" "$prefix/share/geohaz/data")
