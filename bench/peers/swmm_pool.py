#!/usr/bin/env python3
"""One canal pool, 24 h, in canalsim and in EPA SWMM 5 (dynamic wave): same geometry, same
nodes, same time step, same inflow steps; prints the downstream depths both compute and the
median wall time of each over interleaved runs.  Run by bench/compare_swmm.sh.

The pool is pool 1 of ASCE test canal 2 (config/sim/asce-canal2.toml: 7 km, trapezoid b = 7 m,
m = 1.5, S0 = 1e-4, n = 0.02, 2.1 m downstream at 11 m3/s), alone: 11 m3/s in, an undershot
gate (w = 7 m, Cd = 0.6) to a free outfall, no offtake.  The inflow steps to 12 m3/s at 1 h and
back at 12 h.  canalsim: Preissmann, dx = 100 m (70 cells), dt = 10 s.  SWMM: 70 conduits of
100 m between 71 junctions, fixed 10 s routing step (VARIABLE_STEP 0), full inertial terms
(INERTIAL_DAMPING NONE), one thread.  The gate is a SWMM outlet with canalsim's free-flow law,
Q = Cd w u sqrt(2 g (y - u)) (FUNCTIONAL/DEPTH, offset u; a SWMM orifice measures the head to the
opening's centroid and adds storage at its node).  SWMM starts from a hotstart file written by an
untimed 24 h run at the steady inflow (its conduits would otherwise start at normal depth);
canalsim solves its steady state at the start of every run, inside the timing.
"""
import argparse
import math
import os
import resource
import statistics
import struct
import subprocess
import sys
import time
import tomllib

G = 9.81
HOURS = 24
STEP_S = 10.0
REPORT_S = 60.0
MAGIC = 516114522  # first and last word of a SWMM 5 binary output file


def pool_from_canal(path):
    with open(path, "rb") as f:
        canal = tomllib.load(f)
    pool = canal["pool"][0]
    structure = pool.get("structure", {})
    if canal.get("upstream", {}).get("type", "flow") != "flow" or \
            structure.get("type", "gate") != "gate" or structure.get("drop_m", 0.0) != 0.0:
        sys.exit(f"swmm_pool: {path}: the first pool must have an inflow upstream and a gate "
                 "without a drop downstream")
    return {
        "length": pool["length_m"], "b": pool["bottom_width_m"], "m": pool["side_slope"],
        "s0": pool["bed_slope"], "n": pool["manning_n"], "depth": pool["target_depth_m"],
        "flow": canal["upstream"]["flow_m3s"], "dx": canal.get("max_dx_m", 100.0),
        "theta": canal.get("theta", 0.6),
        "gate_w": structure.get("width_m", pool["bottom_width_m"]),
        "cd": structure.get("coefficient", 0.6),
    }


def write_canalsim(p, work):
    canal = os.path.join(work, "pool.toml")
    scenario = os.path.join(work, "pool-day.toml")
    with open(canal, "w", encoding="utf-8") as f:
        f.write(f"""name = "swmm-comparison-pool"
max_dx_m = {p['dx']}
theta = {p['theta']}
[upstream]
type = "flow"
flow_m3s = {p['flow']}
[[pool]]
name = "1"
length_m = {p['length']}
bottom_width_m = {p['b']}
side_slope = {p['m']}
bed_slope = {p['s0']}
manning_n = {p['n']}
target_depth_m = {p['depth']}
[pool.structure]
type = "gate"
width_m = {p['gate_w']}
coefficient = {p['cd']}
setting = "steady"
[pool.offtake]
type = "none"
""")
    with open(scenario, "w", encoding="utf-8") as f:
        f.write(f"""duration_s = {HOURS * 3600.0}
output_period_s = {REPORT_S}
time_step_s = {STEP_S}
seed = 1
[[event]]
time_s = 3600.0
target = "inflow"
kind = "step"
value = 1.0
[[event]]
time_s = 43200.0
target = "inflow"
kind = "step"
value = -1.0
[output]
q_out = "pool1.outflow"
depth = "pool1.level_downstream"
""")
    return canal, scenario


def gate_opening(p):
    """Opening u of canalsim's free-flow gate, Q = Cd w u sqrt(2 g (y - u)), passing the steady
    flow at the target depth (bisection on (0, 2y/3], where the flow grows with u)."""
    lo, hi = 1e-9, 2 * p["depth"] / 3
    for _ in range(200):
        u = 0.5 * (lo + hi)
        q = p["cd"] * p["gate_w"] * u * math.sqrt(2 * G * (p["depth"] - u))
        lo, hi = (u, hi) if q < p["flow"] else (lo, u)
    return 0.5 * (lo + hi)


def steady_depths(p, cells):
    """Depths of the steady flow at the cells' ends, upstream from the target depth at the gate:
    the gradually varied flow equation dy/dx = (S0 - Sf) / (1 - Fr^2) (RK4, 10 substeps per
    cell), the starting state SWMM is given (canalsim solves its own)."""
    q, b, m, n, s0 = p["flow"], p["b"], p["m"], p["n"], p["s0"]

    def slope(y):
        area, top = (b + m * y) * y, b + 2 * m * y
        radius = area / (b + 2 * y * math.sqrt(1 + m * m))
        sf = (n * q) ** 2 / (area * area * radius ** (4 / 3))
        return (s0 - sf) / (1 - q * q * top / (G * area ** 3))

    h = -p["length"] / cells / 10
    y, depths = p["depth"], [p["depth"]]
    for _ in range(cells):
        for _ in range(10):
            k1 = slope(y)
            k2 = slope(y + h * k1 / 2)
            k3 = slope(y + h * k2 / 2)
            k4 = slope(y + h * k3)
            y += h * (k1 + 2 * k2 + 2 * k3 + k4) / 6
        depths.append(y)
    return depths[::-1]


def clock(seconds):
    """SWMM's hh:mm:ss (hours past 24 allowed in time series)."""
    seconds = round(seconds)
    return f"{seconds // 3600:02d}:{seconds // 60 % 60:02d}:{seconds % 60:02d}"


def write_swmm(p, work, name, hotstart, steps):
    """Writes WORK/NAME.inp: the pool, the inflow series STEPS ((time_s, flow) points), and
    HOTSTART as ("SAVE" | "USE", path)."""
    cells = math.ceil(p["length"] / p["dx"] - 1e-9)
    dx = p["length"] / cells
    drop = p["s0"] * p["length"]
    u = gate_opening(p)
    end_day, end_s = divmod(int(HOURS * 3600), 86400)
    lines = ["[TITLE]", "canalid bench: one canal pool against canalsim", "",
             "[FILES]", f'{hotstart[0]} HOTSTART "{hotstart[1]}"', "",
             "[OPTIONS]", "FLOW_UNITS CMS", "FLOW_ROUTING DYNWAVE",
             "START_DATE 01/01/2026", "START_TIME 00:00:00",
             "REPORT_START_DATE 01/01/2026", "REPORT_START_TIME 00:00:00",
             f"END_DATE 01/{1 + end_day:02d}/2026", f"END_TIME {clock(end_s)}",
             f"REPORT_STEP {clock(REPORT_S)}", f"WET_STEP {clock(REPORT_S)}",
             f"DRY_STEP {clock(REPORT_S)}", f"ROUTING_STEP {STEP_S:g}",
             "ALLOW_PONDING NO", "INERTIAL_DAMPING NONE", "VARIABLE_STEP 0",
             "LENGTHENING_STEP 0", "SKIP_STEADY_STATE NO", "THREADS 1", ""]
    lines += ["[JUNCTIONS]", ";Name Elevation MaxDepth InitDepth SurDepth Aponded"]
    for i, y in enumerate(steady_depths(p, cells)):
        lines.append(f"J{i} {drop - i * p['s0'] * dx:.6f} 6 {y:.6f} 0 0")
    lines += ["", "[OUTFALLS]", ";Name Elevation Type Gated", "OUT -1 FREE NO", ""]
    lines += ["[CONDUITS]", ";Name From To Length Roughness InOffset OutOffset InitFlow"]
    for i in range(1, cells + 1):
        lines.append(f"C{i} J{i - 1} J{i} {dx:.6f} {p['n']} 0 0 {p['flow']}")
    lines += ["", "[OUTLETS]", ";Name From To Offset Type C1 C2 Gated",
              f"GATE J{cells} OUT {u:.6f} FUNCTIONAL/DEPTH "
              f"{p['cd'] * p['gate_w'] * u * math.sqrt(2 * G):.6f} 0.5 NO", ""]
    lines += ["[XSECTIONS]", ";Link Shape Geom1 Geom2 Geom3 Geom4 Barrels"]
    for i in range(1, cells + 1):
        lines.append(f"C{i} TRAPEZOIDAL 6 {p['b']} {p['m']} {p['m']} 1")
    lines += ["", "[TIMESERIES]"]
    lines += [f"INFLOW {clock(t)} {q}" for t, q in steps]
    lines += ["", "[INFLOWS]", ";Node Constituent TimeSeries", "J0 FLOW INFLOW", "",
              "[REPORT]", "INPUT NO", "CONTROLS NO", "SUBCATCHMENTS NONE", f"NODES J{cells}",
              "LINKS NONE", ""]
    inp = os.path.join(work, name + ".inp")
    with open(inp, "w", encoding="utf-8") as f:
        f.write("\n".join(lines))
    return inp, cells


def inflow_steps(p):
    """The scenario's inflow as SWMM points: SWMM reads an inflow at the start of a routing step,
    canalsim applies an event on the step that ends at its time, so each step is put one
    routing step early to act on the same step."""
    base, high, end = p["flow"], p["flow"] + 1.0, HOURS * 3600.0
    return [(0, base), (3600 - STEP_S, base), (3600, high), (43200 - STEP_S, high),
            (43200, base), (end, base)]


def canalsim_depths(csv):
    with open(csv, encoding="utf-8") as f:
        header = f.readline().strip().split(",")
        col = header.index("depth")
        return [float(line.split(",")[col]) for line in f if line.strip()]


def swmm_depths(out):
    """Depths of the one reported node at each report step, from SWMM's binary output: the
    header's counts, the closing record's results offset and period count, and per period a
    double date then 4-byte values (subcatchments, nodes: depth first, links, 15 system)."""
    with open(out, "rb") as f:
        data = f.read()
    magic, _, _, subcatchments, nodes, links, pollutants = struct.unpack_from("<7i", data, 0)
    results, periods, error, magic_end = struct.unpack_from("<4i", data, len(data) - 16)
    if magic != MAGIC or magic_end != MAGIC or error != 0 or nodes != 1 or periods <= 0:
        sys.exit(f"swmm_pool: {out}: not a clean SWMM output with one reported node")
    period = 8 + 4 * (nodes * (6 + pollutants) + links * (5 + pollutants) + 15)
    if subcatchments != 0 or results + periods * period + 24 != len(data):
        sys.exit(f"swmm_pool: {out}: unexpected layout")
    return [struct.unpack_from("<f", data, results + k * period + 8)[0] for k in range(periods)]


def run_swmm(cmd, out, rpt):
    """Runs runswmm; it exits 0 even on errors, so its output and report are checked."""
    for path in (out, rpt):
        if os.path.exists(path):
            os.remove(path)
    r = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if r.returncode != 0 or "There are errors" in r.stdout or not os.path.exists(out):
        report = open(rpt, encoding="utf-8", errors="replace").read() if os.path.exists(rpt) else ""
        errors = [line.strip() for line in report.splitlines() if "ERROR" in line]
        sys.exit(f"swmm_pool: {' '.join(cmd)} failed: {r.stdout.strip()} {' '.join(errors[:5])}")


def run_canalsim(cmd):
    r = subprocess.run(cmd, capture_output=True, text=True, check=False)
    if r.returncode != 0:
        sys.exit(f"swmm_pool: {' '.join(cmd)} failed ({r.returncode}): {r.stderr.strip()}")


def continuity_error(rpt):
    """SWMM's flow routing continuity error (%), from its report."""
    with open(rpt, encoding="utf-8", errors="replace") as f:
        text = f.read()
    flow = text[text.find("Flow Routing Continuity"):]
    for line in flow.splitlines():
        if line.strip().startswith("Continuity Error (%)"):
            return float(line.split()[-1])
    return float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n", maxsplit=1)[0])
    ap.add_argument("--canalsim", required=True)
    ap.add_argument("--runswmm", required=True)
    ap.add_argument("--canal", required=True, help="canal file whose first pool is simulated")
    ap.add_argument("--work", required=True, help="folder for the inputs and outputs (made)")
    ap.add_argument("--repetitions", type=int, default=5)
    a = ap.parse_args()
    if a.repetitions < 1:
        sys.exit("swmm_pool: --repetitions must be at least 1")
    os.makedirs(a.work, exist_ok=True)
    p = pool_from_canal(a.canal)
    canal, scenario = write_canalsim(p, a.work)
    hotstart = os.path.join(a.work, "steady.hsf")
    spin, _ = write_swmm(p, a.work, "spin-up", ("SAVE", hotstart),
                         [(0, p["flow"]), (HOURS * 3600.0, p["flow"])])
    inp, cells = write_swmm(p, a.work, "pool", ("USE", hotstart), inflow_steps(p))
    csv = os.path.join(a.work, "canalsim.csv")
    rpt, out = os.path.join(a.work, "pool.rpt"), os.path.join(a.work, "pool.out")
    run_swmm([a.runswmm, spin, os.path.join(a.work, "spin-up.rpt"),
              os.path.join(a.work, "spin-up.out")], os.path.join(a.work, "spin-up.out"),
             os.path.join(a.work, "spin-up.rpt"))
    runs = {
        "canalsim": lambda: run_canalsim([a.canalsim, "run", "-q", "--canal", canal, "--scenario",
                                          scenario, "--out", csv]),
        "swmm": lambda: run_swmm([a.runswmm, inp, rpt, out], out, rpt),
    }
    wall = {"canalsim": [], "swmm": []}
    cpu = {"canalsim": [], "swmm": []}
    for name in runs:  # one untimed run of each first (page cache, CPU frequency)
        runs[name]()
    for k in range(a.repetitions):  # interleaved, the order alternating
        for name in (("canalsim", "swmm") if k % 2 == 0 else ("swmm", "canalsim")):
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            t = time.perf_counter()
            runs[name]()
            wall[name].append(time.perf_counter() - t)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu[name].append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    y_ours, y_peer = canalsim_depths(csv), swmm_depths(out)
    per_hour = int(3600 / REPORT_S)
    print(f"pool: {p['length']:.0f} m, {cells} cells of {p['length'] / cells:.0f} m,"
          f" dt {STEP_S:g} s,"
          f" {HOURS} h; inflow {p['flow']:g} -> {p['flow'] + 1:g} m3/s at 1 h, back at 12 h;"
          f" SWMM continuity error {continuity_error(rpt):.3f} %")
    for hour in (1, 6, 12, 18, 24):
        i = hour * per_hour
        ours_y = y_ours[i] if i < len(y_ours) else float("nan")
        peer_y = y_peer[i - 1] if 0 < i <= len(y_peer) else float("nan")  # from the 1st step
        print(f"downstream depth at {hour:2d} h: canalsim {ours_y:.4f} m, SWMM {peer_y:.4f} m")
    for label, times in (("wall", wall), ("CPU (user + system)", cpu)):
        mo, mp = statistics.median(times["canalsim"]), statistics.median(times["swmm"])
        print(f"{label}, median of {a.repetitions}: canalsim {mo * 1e3:.0f} ms, SWMM"
              f" {mp * 1e3:.0f} ms; canalsim runs at {mp / mo:.2f} x SWMM's speed")


if __name__ == "__main__":
    main()
