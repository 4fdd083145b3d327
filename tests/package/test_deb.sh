#!/usr/bin/env bash
# ctest package_deb (issue 37): build the Debian packages with CPack (one per component), check
# their names and control fields (maintainer, python3 range, Open MPI only in geohaz-ensemble,
# dpkg-shlibdeps dependencies), run lintian on them (its remaining findings are listed in
# docs/install.md; an error fails the test), unpack them all into one clean root (dpkg-deb -x, as
# dpkg would install them under /) and run from there, outside the source tree: every app's
# --version, a short debris-runout run on the installed example data, the man pages (gzipped, SEE
# ALSO naming /usr/share/geohaz) and the Python module.
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
pyver=$("$python" -c 'import sys; print(f"{sys.version_info[0]}.{sys.version_info[1]}")')
pynext=$("$python" -c 'import sys; print(f"{sys.version_info[0]}.{sys.version_info[1] + 1}")')
declare -A want=(
  [geohaz]="libgdal libhdf5 libboost-program-options libgomp1"
  [geohaz-ensemble]="libopenmpi geohaz (= $version)"
  [python3-geohaz]="python3 (>= $pyver) python3 (<< $pynext) python3-numpy libgdal"
  [libgeohaz-dev]="libgdal-dev libeigen3-dev cmake"
)
for pkg in "${!want[@]}"; do
  deb=$tmp/cpack/${pkg}_${version}_${arch}.deb
  [ -f "$deb" ] || { ls "$tmp/cpack"; fail "no ${pkg}_${version}_${arch}.deb"; }
  depends=$(dpkg-deb -f "$deb" Depends)
  echo "test_deb: $pkg ($(du -k "$deb" | cut -f1) kB) Depends: $depends"
  read -r -a words <<<"${want[$pkg]}"
  case $pkg in
    python3-geohaz)
      for p in "python3 (>= $pyver)" "python3 (<< $pynext)" python3-numpy libgdal; do
        [[ $depends == *"$p"* ]] || fail "$pkg: Depends lacks '$p'"
      done ;;
    geohaz-ensemble)
      for p in libopenmpi "geohaz (= $version)"; do
        [[ $depends == *"$p"* ]] || fail "$pkg: Depends lacks '$p'"
      done ;;
    *)
      for p in "${words[@]}"; do [[ $depends == *"$p"* ]] || fail "$pkg: Depends lacks '$p'"; done ;;
  esac
  if [ "$pkg" != geohaz-ensemble ]; then
    [[ $depends != *openmpi* && $depends != *libmpi* ]] || fail "$pkg depends on MPI: $depends"
  fi
  maint=$(dpkg-deb -f "$deb" Maintainer)
  [[ $maint == *"<"*"@"*">" ]] || fail "$pkg: Maintainer '$maint' is not 'Name <email>'"
  dpkg-deb -x "$deb" "$tmp/root"
done

if command -v lintian >/dev/null; then
  # Findings by tag, for docs/install.md; errors (E:) fail the test, except those listed there as
  # accepted (a local build has no changelog or copyright file from the Debian archive).
  lintian --tag-display-limit 0 "$tmp"/cpack/*.deb >"$tmp/lintian.log" 2>&1 || true
  sed -E 's/^([EWIP]): [^ ]+: ([^ ]+).*/\1 \2/' "$tmp/lintian.log" | sort | uniq -c | sed 's/^/test_deb: lintian /'
  accepted='bogus-mail-host|no-copyright-file|no-changelog|debian-changelog-file-missing|changelog-file-missing-in-native-package|extended-description-is-empty|unstripped-binary-or-object|shared-library-lacks-version|dir-or-file-in-opt'
  errors=$(grep -E '^E: ' "$tmp/lintian.log" | grep -Ev "$accepted" || true)
  [ -z "$errors" ] || { echo "$errors"; fail "lintian errors (above)"; }
else
  echo "test_deb: lintian not installed (scripts/setup installs it): not run"
fi

root=$tmp/root
for f in usr/bin/debris-runout usr/bin/sph-slope usr/bin/dem-avalanche usr/bin/geohaz-report usr/bin/geohaz-ensemble \
         usr/lib/libgeohaz_core.a usr/include/geohaz/runout/run.hpp usr/lib/cmake/geohaz/geohazConfig.cmake \
         usr/lib/python3/dist-packages/geohaz/__init__.py usr/share/geohaz/data/runout/alr.toml \
         usr/share/geohaz/docs/python.md usr/share/bash-completion/completions/sph-slope \
         usr/share/man/man1/debris-runout.1.gz usr/share/man/man1/geohaz-ensemble.1.gz; do
  [ -e "$root/$f" ] || fail "not in the packages: $f"
done
zcat "$root/usr/share/man/man1/debris-runout.1.gz" | grep -q '/usr/share/geohaz/data' || fail "man page: SEE ALSO lacks /usr/share/geohaz/data"
! zcat "$root"/usr/share/man/man1/*.gz | grep -q '@GEOHAZ_DATADIR@' || fail "man page: placeholder left"

cd "$tmp"  # outside the source tree
apps=(sph-slope debris-runout dem-avalanche geohaz-report geohaz-ensemble)
# The SPH app on MPI ranks goes into geohaz-ensemble when the build has it (GEOHAZ_MPI, Open MPI found).
if [ -x "$build/apps/sph-slope/sph-slope-mpi" ]; then
  apps+=(sph-slope-mpi)
  [ -e "$root/usr/share/man/man1/sph-slope-mpi.1.gz" ] || fail "not in the packages: sph-slope-mpi's man page"
  listing=$(dpkg-deb -c "$tmp/cpack/geohaz-ensemble_${version}_${arch}.deb")
  [[ $listing == *usr/bin/sph-slope-mpi* ]] || fail "sph-slope-mpi is not in geohaz-ensemble"
fi
for app in "${apps[@]}"; do
  out=$("$root/usr/bin/$app" --version)
  [ "$out" = "$app $version" ] || fail "$app --version printed '$out'"
done
echo "test_deb: every app's --version: $version"
# A short run of the installed app on the installed data (the small valley, 5 s).
"$root/usr/bin/debris-runout" --config "$root/usr/share/geohaz/data/runout/valley_small.toml" --duration 5 \
  --quiet --threads 1 --out "$tmp/run" >"$tmp/run.log" 2>&1 || { cat "$tmp/run.log"; fail "debris-runout run failed"; }
[ -s "$tmp/run/max_depth.tif" ] && [ -s "$tmp/run/summary.json" ] || fail "the run wrote no max_depth.tif / summary.json"
# The installed Python module, found the way Debian's python3 finds /usr/lib/python3/dist-packages.
PYTHONPATH=$root/usr/lib/python3/dist-packages GEOHAZ_BIN_DIR=$root/usr/bin "$python" - "$root" "$version" "$tmp/run" <<'PY'
import sys, pathlib
root, version, run = pathlib.Path(sys.argv[1]), sys.argv[2], sys.argv[3]
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
r = geohaz.runout.run(config=data / "valley_small.toml", duration=5.0, particles=False, threads=1)
assert r["maps"]["max_depth"].shape == (200, 400)
assert abs(r["summary"]["simulated_time_s"] - 5.0) < 1e-9
# The installed app's run, read back: the same 5 s, so the same maximum depth (Float32 on disk).
back = geohaz.read_run(run)
assert abs(back["summary"]["simulated_time_s"] - 5.0) < 1e-9
import numpy as np
np.testing.assert_array_equal(back["maps"]["max_depth"], r["maps"]["max_depth"].astype(np.float32).astype(float))
print("test_deb: import geohaz", geohaz.__version__, "from", geohaz.__file__, "a 5 s run and read_run: ok")
PY
