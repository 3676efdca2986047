#!/usr/bin/env bash
# Whole-process comparison of issue 4: `canalid identify --model arx --online` over a 100k-sample
# CSV against the same exponential-forgetting RLS loop in numpy (bench/peers/rls_numpy.py).
# Checks that both give the same ARX(2,2,1) parameters (1e-6 relative), then prints the wall
# times of each and the speed ratio from interleaved rounds (below).
# Usage: bench/compare_online_numpy.sh [BUILD_DIR] [SAMPLES] [FORGETTING] [ROUNDS (default 7)]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
samples=${2:-100000}
lambda=${3:-0.999}
rounds=${4:-7}
canalid=$build/daemon/canalid/canalid
python=/usr/bin/python3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
csv=$work/arx100k.csv

# A stable ARX(2,2,1) plant, y(t) = 1.5 y(t-1) - 0.7 y(t-2) + u(t-1) + 0.5 u(t-2) + e(t), driven
# by a seeded random binary input, e ~ N(0, 0.1^2).  Seeded: the same file every run.
"$python" - "$csv" "$samples" <<'PY'
import sys
import numpy as np
path, n = sys.argv[1], int(sys.argv[2])
rng = np.random.default_rng(4)
u = np.where(rng.random(n) < 0.5, -1.0, 1.0)
e = 0.1 * rng.standard_normal(n)
y = np.zeros(n)
for t in range(2, n):
    y[t] = 1.5 * y[t - 1] - 0.7 * y[t - 2] + u[t - 1] + 0.5 * u[t - 2] + e[t]
np.savetxt(path, np.column_stack([np.arange(n) * 1.0, u, y]), delimiter=",",
           header="time_s,u,y", comments="", fmt="%.17g")
PY

canalid_cmd=("$canalid" identify --model arx --input "$csv" --u u --y y --na 2 --nb 2 --nk 1
             --online --method exponential --forgetting "$lambda")
numpy_cmd=("$python" "$root/bench/peers/rls_numpy.py" "$csv" --forgetting "$lambda")

"${canalid_cmd[@]}" >"$work/canalid.json"
"${numpy_cmd[@]}" >"$work/numpy.json"
"$python" - "$work/canalid.json" "$work/numpy.json" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))
n = json.load(open(sys.argv[2]))
ours = c["a"] + c["b_coeffs"][0]
theirs = n["a"] + n["b"]
worst = max(abs(x - y) / abs(y) for x, y in zip(ours, theirs))
print("canalid [a1 a2 b1 b2] =", ours)
print("numpy   [a1 a2 b1 b2] =", theirs)
print("largest relative difference: %.3g" % worst)
if worst > 1e-6:
    sys.exit("parameters differ by more than 1e-6 relative")
PY

echo "samples: $samples, forgetting: $lambda"
# Interleaved rounds, so that both sides of each ratio see the same machine (a shared VM's speed
# drifts by tens of % within a minute): each round times canalid 5 times (its median) and numpy
# once, with Python's perf_counter around the process; the round's ratio is numpy / canalid.
# Prints the medians over the rounds.
"$python" - "$rounds" "${#canalid_cmd[@]}" "${canalid_cmd[@]}" "${numpy_cmd[@]}" <<'PY'
import statistics, subprocess, sys, time
rounds, count = int(sys.argv[1]), int(sys.argv[2])
canalid, numpy = sys.argv[3:3 + count], sys.argv[3 + count:]
def wall(cmd):
    t = time.perf_counter()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, check=True)
    return time.perf_counter() - t
ours, theirs, ratios = [], [], []
for _ in range(rounds):
    c = statistics.median(wall(canalid) for _ in range(5))
    n = wall(numpy)
    ours.append(c)
    theirs.append(n)
    ratios.append(n / c)
print("canalid identify --model arx --online: %.4f s (median of %d rounds, each the median of 5)"
      % (statistics.median(ours), rounds))
print("numpy RLS loop (bench/peers/rls_numpy.py): %.4f s (median of %d rounds)"
      % (statistics.median(theirs), rounds))
print("speed ratio numpy / canalid: %.1f x (median of the rounds' ratios; range %.1f-%.1f)"
      % (statistics.median(ratios), min(ratios), max(ratios)))
PY
