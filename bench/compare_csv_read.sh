#!/usr/bin/env bash
# Reading a 100k-row CSV (time_s and two columns, 17 significant digits, as canalid export and
# numpy.savetxt write them): drivers::CsvTable::Read (build/bench/csv_bench, median of 5) against
# numpy.loadtxt (C parser, numpy >= 1.23; median of 5) on the same file, in one run.
# Usage: bench/compare_csv_read.sh [BUILD_DIR] [ROWS]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
rows=${2:-100000}
python=/usr/bin/python3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
csv=$work/table.csv
"$python" - "$csv" "$rows" <<'PY'
import sys
import numpy as np
path, n = sys.argv[1], int(sys.argv[2])
rng = np.random.default_rng(4)
u = np.where(rng.random(n) < 0.5, -1.0, 1.0)
y = np.cumsum(0.01 * rng.standard_normal(n))
np.savetxt(path, np.column_stack([np.arange(n) * 1.0, u, y]), delimiter=",",
           header="time_s,u,y", comments="", fmt="%.17g")
PY
ours=$(CANALID_CSV_BENCH_INPUT=$csv "$build/bench/csv_bench" --benchmark_repetitions=5 \
         --benchmark_report_aggregates_only=true --benchmark_format=json |
       "$python" -c 'import json,sys
r = [b for b in json.load(sys.stdin)["benchmarks"] if b["name"].endswith("_median")][0]
print(r["real_time"] / 1e3)')  # ms -> s
numpy=$("$python" - "$csv" <<'PY'
import sys, time
import numpy as np
times = []
for _ in range(5):
    t = time.perf_counter()
    np.loadtxt(sys.argv[1], delimiter=",", skiprows=1)
    times.append(time.perf_counter() - t)
print(sorted(times)[2])
PY
)
bytes=$(stat -c %s "$csv")
"$python" - "$ours" "$numpy" "$bytes" "$rows" <<'PY'
import sys
ours, numpy, size, rows = float(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
print("rows: %d, %.1f MB" % (rows, size / 1e6))
print("CsvTable::Read:  %.1f ms, %.0f MB/s (median of 5)" % (ours * 1e3, size / ours / 1e6))
print("numpy.loadtxt:   %.1f ms, %.0f MB/s (median of 5)" % (numpy * 1e3, size / numpy / 1e6))
print("speed ratio numpy / canalid: %.1f x" % (numpy / ours))
PY
