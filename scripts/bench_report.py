#!/usr/bin/env python3
"""Turn Google Benchmark JSON into bench/RESULTS.md: every figure beside its baseline.

Usage: bench_report.py results.json RESULTS.md
"""
import json
import platform
import sys


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(sys.argv[1]) as f:
        data = json.load(f)
    ctx = data.get("context", {})
    # Median over repetitions where present, else the single run.
    times = {}
    for b in data["benchmarks"]:
        name = b.get("run_name", b["name"])
        if b.get("aggregate_name") not in (None, "median"):
            continue
        unit = {"ns": 1e-3, "us": 1.0, "ms": 1e3}[b.get("time_unit", "ns")]
        times[name] = b["cpu_time"] * unit
    out = ["# Benchmark results", ""]
    out.append(f"Machine: {platform.machine()}, {ctx.get('num_cpus', '?')} CPUs at "
               f"{ctx.get('mhz_per_cpu', '?')} MHz; run {ctx.get('date', '?')}; "
               f"build {ctx.get('library_build_type', '?')}. Times are CPU µs, median of 3.")
    out += ["", "## Filter step (predict over one 30 Hz frame interval + pose update)", "",
            "| model | SR-DD2 µs | EKF µs | UKF µs | DD2 / EKF | target DD2 ≤ 10 µs |",
            "|---|---|---|---|---|---|"]
    models = sorted({n.split("/")[1] for n in times if n.startswith("FilterStep/")})
    for m in models:
        d, e, u = (times.get(f"FilterStep/{m}/{f}") for f in ("dd2", "ekf", "ukf"))
        ratio = d / e if d and e else float("nan")
        out.append(f"| {m} | {d:.2f} | {e:.2f} | {u:.2f} | {ratio:.2f} | "
                   f"{'met' if d <= 10 else 'NOT met'} |")
    out += ["", "## Propagation (one frame interval, exact arcs)", "", "| model | µs |", "|---|---|"]
    for m in models:
        out.append(f"| {m} | {times.get(f'Propagate/{m}', float('nan')):.3f} |")
    out += ["", "## SR-DD2 step against augmented-state size (diffdrive + effects)", "",
            "| effects | µs |", "|---|---|"]
    for k in range(4):
        v = times.get(f"BM_DiffDriveStepVsStateSize/{k}")
        if v is not None:
            out.append(f"| {k} | {v:.2f} |")
    with open(sys.argv[2], "w") as f:
        f.write("\n".join(out) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
