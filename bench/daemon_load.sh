#!/usr/bin/env bash
# canalidd under a full ASCE canal 2 load: all 8 pool records of canalsim's PLC polled at 10 Hz
# (8 float input channels each = 64 channels, plus one writable gate setpoint per reach and the
# heartbeat), 8 reaches each running the online models ONLINE_MODELS (default "id", "frac-foptd":
# the ID bank and the fractional alpha bank), against canalsim serve at --time-scale 10
# (poll_period_s 0.1 wall s = 1 plant s per sample).  No experiment runs.
#
# The peer, in the same run and window: mbpoll, a bare Modbus poller (no decoding into channels,
# no estimators, no bus), reading the same registers at the same 10 Hz: the 64 input floats as
# two requests of 32, and the 8 gate setpoints as one request of 16 holding floats (300-331: the
# setpoints and the fields between them), three mbpoll processes whose CPU is summed.  The
# ratio says what identification and publishing cost over polling alone.
#
# Prints:
#   - start to READY: wall time from exec of canalidd to its "answers: ready" log line, 5 runs
#     and their median;
#   - over a run of DURATION_S wall seconds (default 60) after WARMUP_S (default 205: the ID banks
#     only update once max_delay_s of plant time has passed, 198 wall s for pool 1, so the
#     measurement starts once all eight are updating): canalidd's CPU seconds (user + system,
#     /proc/<pid>/stat), its peak RSS (VmHWM, /proc/<pid>/status), the number of polls, the mean
#     libmodbus round trip per poll (sample_t.round_trip_s from the LCM log the daemon writes) and
#     the CPU time per poll cycle; the peer's CPU over the same window and the ratio.
#
# RESULTS_POLLERS=N (default 0): canalidd also serves its results register map
# (docs/results-register-map.md) and N mbpoll masters read it at 10 Hz each (125 registers of
# reach 0's (pool1's) block per request) from the start of the warm-up: canalidd's CPU and sample intervals
# then include serving them.
#
# Usage: bench/daemon_load.sh [build-dir]
#        (DURATION_S=60 RUNS=5 ONLINE_MODELS='"id", "frac-foptd"' RESULTS_POLLERS=0)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$here/build}
duration_s=${DURATION_S:-60}
warmup_s=${WARMUP_S:-205}
runs=${RUNS:-5}
online_models=${ONLINE_MODELS:-'"id", "frac-foptd"'}
results_pollers=${RESULTS_POLLERS:-0}
work=$(mktemp -d)
trap 'kill $(jobs -p) 2>/dev/null || true' EXIT

"$build/sim/canalsim" serve --canal "$here/config/sim/asce-canal2.toml" \
  --plc "$here/config/sim/plc/asce2.toml" --listen 127.0.0.1:0 --time-scale 10 \
  >"$work/canalsim.log" 2>&1 &
sim_pid=$!
for _ in $(seq 200); do
  grep -q 'listening on 127.0.0.1:' "$work/canalsim.log" && break
  sleep 0.05
done
port=$(grep -o 'listening on 127.0.0.1:[0-9]*' "$work/canalsim.log" | head -1 | sed 's/.*://')
[ -n "$port" ] || { cat "$work/canalsim.log"; exit 1; }

# The configuration: pool record r at input float 300 + 16 r + 2 field; the gate at the head of
# pool r + 1 is the downstream structure of record r - 1 (holding float 300 + 4 (r - 1)); pool 1
# has an imposed inflow and no gate at its head, so its actuator here is its own downstream gate
# (never moved: no experiment).  Delays from the IDZ reference (high regime).
delays=(1582.8 682.0 690.9 953.7 971.9 754.3 513.8 526.3)
flows=(11.0 10.0 9.0 8.0 7.0 6.0 5.0 4.0)
fields=(inflow outflow level gate_position gate_setpoint_read upstream_level offtake_flow
  structure_flow)
roles=(flow flow level gate gate level flow flow)
units=(m3/s m3/s m m m m m3/s m3/s)
config=$work/canalidd.toml
{
  cat <<EOF
[daemon]
state_directory = "$work/state"
log_level = "info"
time_scale = 10.0

[daemon.heartbeat]
channel = "heartbeat"
period_s = 0.1

[lcm]
url = ""
channel_prefix = "CANALID_LOAD_"

[[plc]]
name = "asce2"
transport = "tcp"
host = "127.0.0.1"
port = $port
unit_id = 1
connect_timeout_s = 1.0
response_timeout_s = 0.05
poll_period_s = 0.1
backoff_initial_s = 0.5
backoff_max_s = 5.0

[[channel]]
name = "heartbeat"
plc = "asce2"
role = "heartbeat"
register = "holding"
address = 0
type = "u16"
writable = true
setpoint_min = 0.0
setpoint_max = 65535.0
max_rate_per_s = inf
EOF
  for r in $(seq 0 7); do
    for f in $(seq 0 7); do
      cat <<EOF

[[channel]]
name = "pool$((r + 1))_${fields[$f]}"
plc = "asce2"
role = "${roles[$f]}"
register = "input"
address = $((300 + 16 * r + 2 * f))
type = "f32"
word_order = "high_first"
unit = "${units[$f]}"
valid_min = -1.0
valid_max = 55.0
EOF
    done
    cat <<EOF

[[channel]]
name = "gate$((r + 1))_setpoint"
plc = "asce2"
role = "gate"
register = "holding"
address = $((300 + 4 * r))
type = "f32"
word_order = "high_first"
unit = "m"
valid_min = 0.0
valid_max = 2.5
writable = true
setpoint_min = 0.0
setpoint_max = 2.0
max_rate_per_s = 0.005
EOF
  done
  for r in $(seq 0 7); do
    actuator=gate$((r > 0 ? r : 1))_setpoint
    delay=${delays[$r]}
    # The bank holds at most 2000 delays (1 plant s each here): 1.25 x the reference delay.
    max_delay=$(awk -v d="$delay" 'BEGIN { m = 1.25 * d; if (m > 1990) m = 1990; print m }')
    cat <<EOF

[[reach]]
name = "pool$((r + 1))"
inflow = "pool$((r + 1))_inflow"
outflow = "pool$((r + 1))_outflow"
level = "pool$((r + 1))_level"
actuator = "$actuator"
nominal_inflow_m3s = ${flows[$r]}
expected_delay_s = $delay
level_min_m = 0.1
level_max_m = 3.0
online_models = [$online_models]
max_delay_s = $max_delay
closed_loop = "off"
EOF
  done
  printf '\n[commands]\nenabled = false\n'
  if [ "$results_pollers" -gt 0 ]; then printf '\n[results]\nlisten = "127.0.0.1:0"\n'; fi
} >"$config"
mkdir -p "$work/state"
"$build/daemon/canalidd/canalidd" --config "$config" --check-config

daemon=$build/daemon/canalidd/canalidd
# Start to READY, `runs` times: the daemon is stopped (SIGTERM) once it is ready.
ready=()
for i in $(seq "$runs"); do
  log=$work/ready-$i.log
  t0=$(date +%s.%N)
  LCM_DEFAULT_URL="file://$work/ready-$i.lcmlog?mode=w" "$daemon" --config "$config" >"$log" 2>&1 &
  pid=$!
  while ! grep -q 'answers: ready' "$log"; do sleep 0.002; done
  t1=$(date +%s.%N)
  kill -TERM "$pid"
  wait "$pid" || true
  ready+=("$(awk -v a="$t0" -v b="$t1" 'BEGIN { printf "%.3f", b - a }')")
done
printf 'start to READY (s): %s; median %s\n' "${ready[*]}" \
  "$(printf '%s\n' "${ready[@]}" | sort -n | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }')"

# The load run.
lcmlog=$work/load.lcmlog
LCM_DEFAULT_URL="file://$lcmlog?mode=w" "$daemon" --config "$config" >"$work/load.log" 2>&1 &
pid=$!
while ! grep -q 'answers: ready' "$work/load.log"; do sleep 0.01; done
clk=$(getconf CLK_TCK)
cpu_ready=$(awk '{ print $14 + $15 }' "/proc/$pid/stat")
# The peer, polling through the warm-up so that it is steady when the window starts.
peers=()
map_pollers=()
command -v mbpoll >/dev/null || { echo "daemon_load: mbpoll is missing (scripts/setup installs it)"; exit 1; }
# The gate setpoint of record r is holding float 300 + 4 r: 16 floats from 300 cover all 8.
for args in "-t 3:float -r 300 -c 32" "-t 3:float -r 364 -c 32" "-t 4:float -r 300 -c 16"; do
  # shellcheck disable=SC2086  # the arguments are split on purpose
  mbpoll -m tcp -a 1 -p "$port" -0 -B -l 100 -o 0.05 $args 127.0.0.1 >/dev/null 2>&1 &
  peers+=($!)
done
peer_cpu() {
  for p in "${peers[@]}"; do
    [ -r "/proc/$p/stat" ] || { echo "daemon_load: mbpoll (pid $p) stopped" >&2; exit 1; }
    awk '{ print $14 + $15 }' "/proc/$p/stat"
  done | awk '{ s += $1 } END { print s }'
}
if [ "$results_pollers" -gt 0 ]; then
  map_port=$(grep -o 'results map: serving .* on 127.0.0.1:[0-9]*' "$work/load.log" | sed 's/.*://')
  [ -n "$map_port" ] || { echo "daemon_load: no results map in the log"; cat "$work/load.log"; exit 1; }
  for _ in $(seq "$results_pollers"); do
    mbpoll -m tcp -a 1 -p "$map_port" -0 -l 100 -o 1 -t 3 -r 1000 -c 125 127.0.0.1 >/dev/null 2>&1 &
    map_pollers+=($!)
  done
  echo "results map on port $map_port: $results_pollers mbpoll masters at 10 Hz each"
fi
sleep "$warmup_s"
cpu0=$(awk '{ print $14 + $15 }' "/proc/$pid/stat")
peer0=$(peer_cpu)
echo "canalidd CPU over the warm-up ($warmup_s s): $(awk -v a="$cpu_ready" -v b="$cpu0" \
  -v c="$clk" 'BEGIN { printf "%.2f", (b - a) / c }') s"
sleep "$duration_s"
cpu1=$(awk '{ print $14 + $15 }' "/proc/$pid/stat")
peer1=$(peer_cpu)
kill -TERM "${peers[@]}" "${map_pollers[@]}"
wait "${peers[@]}" "${map_pollers[@]}" 2>/dev/null || true
hwm=$(awk '/VmHWM/ { print $2 }' "/proc/$pid/status")
kill -TERM "$pid"
wait "$pid" || true
kill -TERM "$sim_pid"
wait "$sim_pid" || true

# sample_t from the LCM log (LCM log format and the sample_t encoding: big-endian, fingerprint,
# utime, sequence, source, reach, status, exception_code, round_trip_s).
python3 - "$lcmlog" "$cpu0" "$cpu1" "$clk" "$hwm" "$duration_s" "$peer0" "$peer1" <<'EOF'
import struct, sys
path, cpu0, cpu1, clk, hwm, duration, peer0, peer1 = sys.argv[1:]
data = open(path, 'rb').read()
at, trips, utimes = 0, [], []
while at + 28 <= len(data):
    sync, _, _, clen, dlen = struct.unpack_from('>IqqII', data, at)
    assert sync == 0xEDA1DA01
    channel = data[at + 28:at + 28 + clen].decode()
    body = data[at + 28 + clen:at + 28 + clen + dlen]
    at += 28 + clen + dlen
    if not channel.endswith('SAMPLE_asce2'):
        continue
    p = 8
    utime, _ = struct.unpack_from('>qq', body, p); p += 16
    for _ in range(2):
        n, = struct.unpack_from('>i', body, p); p += 4 + n
    status, _, trip = struct.unpack_from('>iif', body, p)
    if status == 0:
        trips.append(trip)
        utimes.append(utime)
cpu_s = (float(cpu1) - float(cpu0)) / float(clk)
polls = len(trips)
trips.sort()
rate = polls / ((utimes[-1] - utimes[0]) * 1e-6) if polls > 1 else 0
print(f'polls ok: {polls} ({rate:.2f} per s over the log)')
print(f'round trip per poll (s): mean {sum(trips) / polls:.6f}, median {trips[polls // 2]:.6f}, '
      f'p99 {trips[int(0.99 * polls)]:.6f}')
gaps = sorted((b - a) * 1e-6 for a, b in zip(utimes, utimes[1:]))
if gaps:
    print(f'sample interval (s): median {gaps[len(gaps) // 2]:.4f}, '
          f'p99 {gaps[int(0.99 * len(gaps))]:.4f}, max {gaps[-1]:.4f}')
print(f'canalidd CPU over {duration} s: {cpu_s:.2f} s ({100 * cpu_s / float(duration):.1f} % of '
      f'one core); per poll cycle {1e3 * cpu_s / (float(duration) * rate):.3f} ms')
print(f'canalidd peak RSS (VmHWM): {int(hwm) / 1024:.1f} MiB')
peer_s = (float(peer1) - float(peer0)) / float(clk)
print(f'peer (3 x mbpoll, same registers at 10 Hz) CPU over {duration} s: {peer_s:.2f} s; '
      f'canalidd / peer: {cpu_s / peer_s:.2f}' if peer_s > 0 else
      f'peer CPU over {duration} s: {peer_s:.2f} s (below the clock tick)')
EOF
echo "files: $work"
