#!/usr/bin/env python3
"""Runs every bench_* program in the build folder and writes bench/RESULTS.md.

Each benchmark is repeated (--repetitions) and the median is reported, with the machine,
date and commit. Usage: ./dev bench  [--repetitions N] [--filter REGEX]
"""
import argparse
import datetime
import json
import math
import os
import platform
import subprocess
import sys


# The heading of the hand-measured part of RESULTS.md, which a rewrite keeps.
KEPT_HEADING = "## Measured by hand"


def machine_description():
    cpu = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    memory = ""
    try:
        with open("/proc/meminfo") as f:
            kib = int(f.readline().split()[1])
            memory = f", {kib / 1024 / 1024:.0f} GiB"
    except (OSError, ValueError, IndexError):
        pass
    return f"{cpu}, {os.cpu_count()} cores{memory}, {platform.system()} {platform.release()}"


def commit(root):
    try:
        return subprocess.check_output(["git", "-C", root, "rev-parse", "--short", "HEAD"], text=True).strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def format_time(value, unit):
    return f"{value:.3f} {unit}"


def problem_size(entry):
    """The size a benchmark instance works on: its `triangles` counter, else its first numeric argument."""
    if isinstance(entry.get("triangles"), (int, float)):
        return float(entry["triangles"])
    parts = entry["run_name"].split("/")
    return float(parts[1]) if len(parts) > 1 and parts[1].isdigit() else None


def scaling_exponents(entries):
    """Least-squares slope of log(median wall time) against log(size) for every benchmark family
    with at least 3 sizes: time ~ size^exponent."""
    families = {}
    for entry in entries:
        size = problem_size(entry)
        if size and entry["real_time"] > 0:
            families.setdefault(entry["run_name"].split("/")[0], []).append((size, entry["real_time"]))
    result = []
    for family, points in families.items():
        if len({size for size, _ in points}) < 3:
            continue
        xs = [math.log(size) for size, _ in points]
        ys = [math.log(time) for _, time in points]
        mean_x, mean_y = sum(xs) / len(xs), sum(ys) / len(ys)
        slope = (sum((x - mean_x) * (y - mean_y) for x, y in zip(xs, ys)) /
                 sum((x - mean_x) ** 2 for x in xs))
        result.append((family, len(points), min(size for size, _ in points), max(size for size, _ in points), slope))
    return result


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--build", required=True)
    parser.add_argument("--repetitions", type=int, default=5)
    parser.add_argument("--filter", default="")
    args = parser.parse_args()
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    bench_dir = os.path.join(args.build, "bench")
    programs = sorted(p for p in os.listdir(bench_dir)
                      if p.startswith("bench_") and os.access(os.path.join(bench_dir, p), os.X_OK))
    sections = []
    for program in programs:
        command = [os.path.join(bench_dir, program), "--benchmark_format=json",
                   f"--benchmark_repetitions={args.repetitions}", "--benchmark_report_aggregates_only=true"]
        if args.filter:
            command.append(f"--benchmark_filter={args.filter}")
        print("running", program, file=sys.stderr)
        result = subprocess.run(command, capture_output=True, text=True)
        if result.returncode != 0:
            sections.append((program, [], f"failed: {result.stderr.strip()[-500:]}", []))
            continue
        rows = []
        medians = [entry for entry in json.loads(result.stdout)["benchmarks"]
                   if entry.get("aggregate_name") == "median"]
        for entry in medians:
            counters = {k: v for k, v in entry.items()
                        if k not in ("name", "run_name", "run_type", "repetitions", "repetition_index",
                                     "threads", "aggregate_name", "aggregate_unit", "iterations",
                                     "real_time", "cpu_time", "time_unit", "family_index",
                                     "per_family_instance_index")}
            rows.append((entry["run_name"], format_time(entry["real_time"], entry["time_unit"]),
                         format_time(entry["cpu_time"], entry["time_unit"]),
                         ", ".join(f"{k}={v:.4g}" for k, v in counters.items() if isinstance(v, (int, float)))))
        sections.append((program, rows, "", scaling_exponents(medians)))
    lines = ["# Benchmark results", "",
             f"- Machine: {machine_description()}",
             f"- Date: {datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}",
             f"- Commit: {commit(root)}",
             f"- Figures: medians over {args.repetitions} repetitions (Google Benchmark), wall and CPU time.",
             "- Produced by `./dev bench` (bench/run_benchmarks.py).", ""]
    for program, rows, error, scaling in sections:
        lines += [f"## {program}", ""]
        if error:
            lines += [error, ""]
            continue
        lines += ["| benchmark | median wall | median CPU | counters |", "|---|---|---|---|"]
        lines += [f"| {n} | {w} | {c} | {k} |" for n, w, c, k in rows]
        lines.append("")
        if scaling:
            lines += ["Scaling: median wall time ~ size^exponent (least squares on log-log; size is the "
                      "`triangles` counter, else the first argument).", "",
                      "| family | sizes | smallest | largest | exponent |", "|---|---|---|---|---|"]
            lines += [f"| {f} | {n} | {lo:.4g} | {hi:.4g} | {e:.2f} |" for f, n, lo, hi, e in scaling]
            lines.append("")
    results_path = os.path.join(root, "bench", "RESULTS.md")
    # Figures measured by hand (whole commands on real runs) follow the kept heading and survive
    # a rewrite.
    kept = ""
    if os.path.exists(results_path):
        with open(results_path) as f:
            previous = f.read()
        if KEPT_HEADING in previous:
            kept = previous[previous.index(KEPT_HEADING):]
    with open(results_path, "w") as f:
        f.write("\n".join(lines))
        if kept:
            f.write("\n" + kept)
    print("wrote bench/RESULTS.md", file=sys.stderr)


if __name__ == "__main__":
    main()
