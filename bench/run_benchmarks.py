#!/usr/bin/env python3
"""Runs every bench_* program in the build folder and writes bench/RESULTS.md.

Each benchmark is repeated (--repetitions) and the median is reported, with the machine,
date and commit. Usage: ./dev bench  [--repetitions N] [--filter REGEX]
"""
import argparse
import datetime
import json
import os
import platform
import subprocess
import sys


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
            sections.append((program, [], f"failed: {result.stderr.strip()[-500:]}"))
            continue
        rows = []
        for entry in json.loads(result.stdout)["benchmarks"]:
            if entry.get("aggregate_name") != "median":
                continue
            counters = {k: v for k, v in entry.items()
                        if k not in ("name", "run_name", "run_type", "repetitions", "repetition_index",
                                     "threads", "aggregate_name", "aggregate_unit", "iterations",
                                     "real_time", "cpu_time", "time_unit", "family_index",
                                     "per_family_instance_index")}
            rows.append((entry["run_name"], format_time(entry["real_time"], entry["time_unit"]),
                         format_time(entry["cpu_time"], entry["time_unit"]),
                         ", ".join(f"{k}={v:.4g}" for k, v in counters.items() if isinstance(v, (int, float)))))
        sections.append((program, rows, ""))
    lines = ["# Benchmark results", "",
             f"- Machine: {machine_description()}",
             f"- Date: {datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}",
             f"- Commit: {commit(root)}",
             f"- Figures: medians over {args.repetitions} repetitions (Google Benchmark), wall and CPU time.",
             "- Produced by `./dev bench` (bench/run_benchmarks.py).", ""]
    for program, rows, error in sections:
        lines += [f"## {program}", ""]
        if error:
            lines += [error, ""]
            continue
        lines += ["| benchmark | median wall | median CPU | counters |", "|---|---|---|---|"]
        lines += [f"| {n} | {w} | {c} | {k} |" for n, w, c, k in rows]
        lines.append("")
    with open(os.path.join(root, "bench", "RESULTS.md"), "w") as f:
        f.write("\n".join(lines))
    print("wrote bench/RESULTS.md", file=sys.stderr)


if __name__ == "__main__":
    main()
