#!/usr/bin/env bash
# DEM beside LAMMPS on the same problem: 10^5 discs settling in a box, linear spring-dashpot with
# tangential history (LAMMPS gran/hooke/history), run back to back and alternating, several times,
# on 1 and on 2 threads (LAMMPS: 1 and 2 MPI ranks). Prints each run's rate and, per thread count,
# the median rates and their ratio. Installs nothing: it needs `lmp` on PATH (Debian: apt-get install
# lammps) and a built bench_dem (scripts/build bench_dem). Timing is only meaningful on an idle
# machine. What makes the two problems the same is listed in docs/performance.md, "DEM beside LAMMPS".
#   bench/peers/dem_vs_lammps.sh [repeats=3] [nx=316 (N = 2 nx * round(nx/2) discs)] [steps=300]
# Environment: BUILD_DIR (default ./build), THREADS (default "1 2"), MPIRUN (default mpirun).
set -euo pipefail
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
repeats=${1:-3}
nx=${2:-316}
steps=${3:-300}
build=${BUILD_DIR:-$root/build}
bench=$build/bench/bench_dem
input=$root/bench/peers/in.discs2d
if ! command -v lmp >/dev/null; then
  echo "dem_vs_lammps: lmp not found; install LAMMPS (Debian: apt-get install lammps) and run again" >&2
  exit 2
fi
if [ ! -x "$bench" ]; then
  echo "dem_vs_lammps: $bench not found; build it first: scripts/build bench_dem" >&2
  exit 2
fi
mpirun=${MPIRUN:-mpirun}
mpi_flags=(--oversubscribe)
[ "$(id -u)" = 0 ] && mpi_flags+=(--allow-run-as-root)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# The same disc count on both sides: LAMMPS's hex lattice holds 2 nx round(nx/2) discs.
n=$(python3 -c "print(2 * $nx * round($nx / 2))")
median() { sort -g | awk '{a[NR] = $1} END {print (NR % 2) ? a[(NR + 1) / 2] : 0.5 * (a[NR / 2] + a[NR / 2 + 1])}'; }

lammps_rate() {  # threads -> particle-steps/s of the timed run (LAMMPS's second "Loop time")
  local t=$1 log=$work/lammps.log
  if [ "$t" = 1 ]; then
    (cd "$work" && OMP_NUM_THREADS=1 lmp -in "$input" -var nx "$nx" -var nsteps "$steps" -log none >"$log")
  else
    (cd "$work" && OMP_NUM_THREADS=1 "$mpirun" "${mpi_flags[@]}" -np "$t" lmp -in "$input" -var nx "$nx" \
      -var nsteps "$steps" -var px "$t" -log none >"$log")
  fi
  awk '/^Loop time of/ {loop = $4; s = $9; atoms = $12} END {printf "%.4g\n", atoms * s / loop}' "$log"
}
geohaz_rate() {  # threads -> particle-steps/s of bench_dem's first case
  "$bench" "$n" "$steps" "$1" settling | awk '/unbonded settling/ {print $5}'
}

echo "dem_vs_lammps: $n discs, $steps timed steps, $repeats alternating repeats; $(lmp -h | awk '/^Large-scale/ {print "LAMMPS" substr($0, index($0, " - ")); exit}')"
for t in ${THREADS:-1 2}; do
  : >"$work/l$t"
  : >"$work/g$t"
  for r in $(seq "$repeats"); do
    l=$(lammps_rate "$t")
    g=$(geohaz_rate "$t")
    echo "$l" >>"$work/l$t"
    echo "$g" >>"$work/g$t"
    printf '  %d thread(s), repeat %d: LAMMPS %s, geohaz %s particle-steps/s\n' "$t" "$r" "$l" "$g"
  done
  lm=$(median <"$work/l$t")
  gm=$(median <"$work/g$t")
  printf '%d thread(s): LAMMPS %s, geohaz %s particle-steps/s (medians); geohaz/LAMMPS = %.2f\n' "$t" "$lm" "$gm" \
    "$(python3 -c "print($gm / $lm)")"
done
