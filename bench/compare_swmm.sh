#!/usr/bin/env bash
# canalsim against EPA SWMM 5 (issue 17): one canal pool (pool 1 of ASCE test canal 2, 7 km,
# 70 cells of 100 m) for 24 h at dt = 10 s with two inflow steps, in both programs, whole process,
# interleaved runs; prints the downstream depths each computes and the median wall times and
# their ratio (bench/peers/swmm_pool.py has the setup of both models).
#
#   bench/compare_swmm.sh [--repetitions N] [SWMM_SOURCE_DIR]
#
# SWMM_SOURCE_DIR is a checkout of EPA SWMM's public source
# (https://github.com/USEPA/Stormwater-Management-Model); its command-line `runswmm` is built
# with CMake (Release) into ${CANALID_BUILD_DIR:-build}/swmm-peer, never in either source tree.
# Without it, prints the comparison recorded in docs/performance.md.  canalsim comes from
# ${CANALID_BUILD_DIR:-build} (scripts/build).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${CANALID_BUILD_DIR:-$root/build}
repetitions=5
source_dir=
while [ $# -gt 0 ]; do
  case "$1" in
    --repetitions) repetitions=${2:?--repetitions needs N}; shift 2 ;;
    -h|--help) sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    -*) echo "compare_swmm: unknown option $1 (see --help)" >&2; exit 2 ;;
    *) [ -z "$source_dir" ] || { echo "compare_swmm: one SWMM_SOURCE_DIR only" >&2; exit 2; }
       source_dir=$1; shift ;;
  esac
done
[[ "$repetitions" =~ ^[1-9][0-9]*$ ]] ||
  { echo "compare_swmm: --repetitions needs a positive integer" >&2; exit 2; }

if [ -z "$source_dir" ]; then
  echo "compare_swmm: no SWMM source given; the comparison recorded in docs/performance.md:"
  grep "^| canalsim against SWMM" "$root/docs/performance.md" || echo "(none recorded)"
  echo "To measure it here: bench/compare_swmm.sh PATH_TO_SWMM_SOURCE"
  exit 0
fi
[ -f "$source_dir/src/run/main.c" ] && [ -f "$source_dir/CMakeLists.txt" ] ||
  { echo "compare_swmm: $source_dir is not EPA SWMM's source (no src/run/main.c)" >&2; exit 2; }
canalsim=$build/sim/canalsim
[ -x "$canalsim" ] || { echo "compare_swmm: no $canalsim (run scripts/build)" >&2; exit 2; }

peer=$build/swmm-peer
log=$peer.log
if [ -f "$peer/CMakeCache.txt" ] &&
   ! grep -qx "CMAKE_HOME_DIRECTORY:INTERNAL=$(cd "$source_dir" && pwd)" \
       "$peer/CMakeCache.txt"; then
  rm -rf "$peer"  # built from another SWMM checkout
fi
if ! { cmake -S "$source_dir" -B "$peer" -G Ninja -DCMAKE_BUILD_TYPE=Release &&
       cmake --build "$peer" --target runswmm; } >"$log" 2>&1; then
  tail -20 "$log" >&2
  echo "compare_swmm: building SWMM failed (log: $log)" >&2
  exit 1
fi
runswmm=$(find "$peer" -name runswmm -type f -perm -u+x -print -quit)
[ -n "$runswmm" ] || { echo "compare_swmm: the SWMM build made no runswmm" >&2; exit 1; }
swmm_version=$(git -C "$source_dir" describe --tags --always 2>/dev/null || echo '?')
echo "compare_swmm: SWMM $swmm_version," \
  "canalsim $(git -C "$root" describe --always --dirty 2>/dev/null || echo '?')"

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
/usr/bin/python3 "$root/bench/peers/swmm_pool.py" --canalsim "$canalsim" --runswmm "$runswmm" \
  --canal "$root/config/sim/asce-canal2.toml" --work "$work" --repetitions "$repetitions"
