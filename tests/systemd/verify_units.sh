#!/usr/bin/env bash
# Checks the unit files in systemd/: `systemd-analyze verify` must print nothing (any stderr line
# is a failure), every service sets MemoryMax= and TasksMax= (lcm-logger's unwritten queue below
# its MemoryMax), and canalidd.service must reach an offline security exposure of 3.0 or less.
# verify needs every ExecStart binary to exist, so the units are checked as copies whose
# /usr/local/bin/ paths point into a temporary root, where each program is a link to the one built
# in this tree (a program that is not built is a failure, not a placeholder).
# Usage: verify_units.sh SOURCE_DIR BINARY_DIR
set -euo pipefail
source_dir=$(cd "$1" && pwd)
binary_dir=$2
max_exposure=3.0
command -v systemd-analyze >/dev/null ||
  { echo "FAIL systemd-analyze is missing (Debian package systemd; scripts/setup installs it)"; exit 1; }

root=$(mktemp -d)
trap 'rm -rf "$root"' EXIT
mkdir -p "$root/bin" "$root/units"
declare -A built=(
  [canalidd]="$binary_dir/daemon/canalidd/canalidd"
  [canalsim]="$binary_dir/sim/canalsim"
)
for program in "${!built[@]}"; do
  if [ ! -x "${built[$program]}" ]; then
    echo "FAIL ${built[$program]} is not built (the units' ExecStart= must name a real program)"
    exit 1
  fi
  ln -s "${built[$program]}" "$root/bin/$program"
done
for unit in "$source_dir"/systemd/*.service; do
  sed "s#/usr/local/bin/#$root/bin/#g" "$unit" >"$root/units/$(basename "$unit")"
done

status=0
cd "$root/units"
for unit in *.service; do
  # A template is verified through an instance of it.
  name=${unit/@.service/@site1.service}
  output=$(systemd-analyze verify --man=no "./$name" 2>&1) || {
    echo "FAIL verify $unit (exit status)"
    status=1
  }
  if [ -n "$output" ]; then
    echo "FAIL verify $unit printed:"
    echo "$output"
    status=1
  else
    echo "ok   verify $unit"
  fi
done

# Every service bounds its memory and tasks (a leak or a runaway stops at the unit, not the host).
for unit in "$source_dir"/systemd/*.service; do
  for key in MemoryMax TasksMax; do
    if grep -qE "^$key=[0-9]+[KMG]?$" "$unit"; then
      echo "ok   $(basename "$unit") sets $key"
    else
      echo "FAIL $(basename "$unit") sets no $key"
      status=1
    fi
  done
done
# lcm-logger's queue of unwritten messages stays inside its unit's MemoryMax.
logger=$source_dir/systemd/canalid-logger@.service
if [ -f "$logger" ]; then
  queue_mb=$(grep -oE -- '--max-unwritten-mb=[0-9]+' "$logger" | cut -d= -f2 || true)
  memory_mb=$(grep -oE '^MemoryMax=[0-9]+M$' "$logger" | grep -oE '[0-9]+' || true)
  if [ -n "$queue_mb" ] && [ -n "$memory_mb" ] && [ "$queue_mb" -lt "$memory_mb" ]; then
    echo "ok   canalid-logger@.service queues ${queue_mb} MB < MemoryMax ${memory_mb} MB"
  else
    echo "FAIL canalid-logger@.service: --max-unwritten-mb (${queue_mb:-none}) must be set below MemoryMax in M (${memory_mb:-none})"
    status=1
  fi
fi

# The original unit (the security check does not need the binary).
line=$(systemd-analyze security --offline=true "$source_dir/systemd/canalidd.service" 2>&1 |
  grep 'Overall exposure level') || {
  echo "FAIL security: no exposure line"
  exit 1
}
exposure=$(sed -E 's/.*: ([0-9.]+).*/\1/' <<<"$line")
if awk -v e="$exposure" -v m="$max_exposure" 'BEGIN { exit !(e <= m) }'; then
  echo "ok   security canalidd.service exposure $exposure <= $max_exposure"
else
  echo "FAIL security canalidd.service exposure $exposure > $max_exposure"
  status=1
fi
exit $status
