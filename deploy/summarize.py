#!/usr/bin/env python3
"""Summarises a deploy/demo results directory: summary.json, summary.txt and gnuplot plots.

Usage: deploy/summarize.py RESULTS_DIR

Each run directory holds frames.csv (one row per frame, written by thinlod-frontend) and
run.json (the run's name and budgets, written by deploy/demo). Only the Python standard
library and gnuplot are used.
"""
import csv
import json
import math
import os
import shutil
import statistics
import subprocess
import sys


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def percentile(values, q):
    values = sorted(v for v in values if math.isfinite(v))
    if not values:
        return math.nan
    k = (len(values) - 1) * q
    lo, hi = math.floor(k), math.ceil(k)
    return values[lo] + (values[hi] - values[lo]) * (k - lo)


def finite_or_none(x):
    return x if isinstance(x, (int, float)) and math.isfinite(x) else None


def summarize_run(run_dir):
    meta_path = os.path.join(run_dir, "run.json")
    meta = json.load(open(meta_path)) if os.path.exists(meta_path) else {}
    rows = read_rows(os.path.join(run_dir, "frames.csv"))
    frames = [int(number(r["frame"])) for r in rows]
    polygons = [number(r["polygons"]) for r in rows]
    snr = [number(r["snr_db"]) for r in rows]
    link = [number(r["link_bytes"]) for r in rows]
    times = [number(r["time_s"]) for r in rows]
    render = [number(r["render_ms"]) for r in rows]
    latency = [number(r["pose_to_frame_ms"]) for r in rows]
    update_latency = [number(r.get("update_latency_ms")) for r in rows]
    # Blank frames (nothing in view: the reference is uniform) have no meaningful SNR.
    finite_snr = [s for s in snr if math.isfinite(s)]
    summary = {
        "name": meta.get("name", os.path.basename(run_dir)),
        "args": meta.get("args", ""),
        "frames": len(rows),
        "snr_db_median": finite_or_none(statistics.median(finite_snr)) if finite_snr else None,
        "snr_db_min": finite_or_none(min(finite_snr)) if finite_snr else None,
        "frames_with_finite_snr": len(finite_snr),
        "polygons_max": max(polygons) if polygons else None,
        "polygons_median": statistics.median(polygons) if polygons else None,
        "render_ms_p99": finite_or_none(percentile(render, 0.99)),
        "render_ms_median": finite_or_none(percentile(render, 0.5)),
        "pose_to_frame_ms_median": finite_or_none(percentile(latency, 0.5)),
        "pose_to_frame_ms_p99": finite_or_none(percentile(latency, 0.99)),
        "update_latency_ms_median": finite_or_none(percentile(update_latency, 0.5)),
        "update_latency_ms_p99": finite_or_none(percentile(update_latency, 0.99)),
        "lockstep": meta.get("lockstep", True),
        "link_bytes_total": sum(x for x in link if math.isfinite(x)),
    }
    budget = meta.get("budget_polygons")
    if budget:
        over = [f for f, p in zip(frames, polygons) if p > budget]
        summary["budget_polygons"] = budget
        summary["frames_over_polygon_budget"] = len(over)
    rate = meta.get("budget_link")
    if rate:
        # Bytes received over every window of one second of trace time.
        worst = 0.0
        for i, t0 in enumerate(times):
            total = sum(b for t, b in zip(times[i:], link[i:]) if t < t0 + 1.0)
            worst = max(worst, total)
        # A token bucket guarantees rate * T + burst over any window of length T.
        burst = meta.get("link_burst", 0.0)
        summary["budget_link_bytes_per_s"] = rate
        summary["link_burst_bytes"] = burst
        summary["link_bytes_max_1s_window"] = worst
        summary["link_bytes_1s_window_bound"] = rate * 1.0 + burst
        span = times[-1] - times[0] if len(times) > 1 else 0.0
        summary["link_bytes_per_s_mean"] = (sum(link) / span) if span > 0 else None
    return summary, rows


def gnuplot(script):
    if shutil.which("gnuplot") is None:
        print("summarize: gnuplot not found; plots skipped", file=sys.stderr)
        return
    subprocess.run(["gnuplot"], input=script.encode(), check=True)


def plot_png(png, width, height, commands):
    """Runs gnuplot `commands` on a CSV with a header, drawing into `png`."""
    gnuplot(f"""
set datafile separator ','
set terminal pngcairo size {width},{height} noenhanced
set output '{png}'
""" + commands)


def plot_run(run_dir, name, rows):
    csv_path = os.path.join(run_dir, "frames.csv")
    png = os.path.join(run_dir, "snr_accuracy_triangles.png")
    # A constant target (a fixed-accuracy run) would give gnuplot an empty y2 range.
    targets = [t for t in (number(r["target_accuracy"]) for r in rows) if math.isfinite(t)]
    y2range = ""
    if targets and min(targets) == max(targets):
        y2range = f"set y2range [{0.9 * targets[0]:g}:{1.1 * targets[0] + 1e-9:g}]"
    # In the style of the paper's Figures 12 and 13: SNR with the target accuracy above,
    # triangles at the frontend below.
    plot_png(png, 900, 650, f"""
set multiplot layout 2,1 title '{name}'
set key outside bottom center horizontal
set grid
set xlabel 'frame'
set ylabel 'SNR (dB)'
set y2label 'target accuracy (rad^-1)'
set y2tics
set ytics nomirror
{y2range}
plot '{csv_path}' using 'frame':'snr_db' with linespoints pt 7 ps 0.4 title 'SNR (dB)', \\
     '' using 'frame':'target_accuracy' axes x1y2 with lines dt 2 title 'target accuracy'
unset y2label
unset y2tics
set ytics mirror
set ylabel 'triangles'
plot '{csv_path}' using 'frame':'polygons' with steps title 'triangles at the frontend'
unset multiplot
""")


def plot_latency(run_dir, name):
    csv_path = os.path.join(run_dir, "frames.csv")
    png = os.path.join(run_dir, "latency.png")
    plot_png(png, 900, 400, f"""
set title '{name}: latency per frame'
set xlabel 'frame'
set ylabel 'ms'
set logscale y
set grid
set key outside bottom center horizontal
plot '{csv_path}' using 'frame':'pose_to_frame_ms' with linespoints pt 7 ps 0.4 title 'pose -> frame', \\
     '' using 'frame':'update_latency_ms' with points pt 6 ps 0.6 title 'pose -> its update visible', \\
     8 with lines dt 2 title 'paper: 8 ms'
""")


def plot_comparison(out_dir, runs):
    png = os.path.join(out_dir, "snr_comparison.png")
    parts = [f"'{os.path.join(out_dir, r, 'frames.csv')}' using 'frame':'snr_db' with lines title '{r}'"
             for r in runs]
    plot_png(png, 900, 500, f"""
set title 'SNR per frame, all runs'
set xlabel 'frame'
set ylabel 'SNR (dB)'
set key outside bottom center horizontal
set grid
plot {', '.join(parts)}
""")


def plot_link(run_dir, name, rate):
    csv_path = os.path.join(run_dir, "frames.csv")
    png = os.path.join(run_dir, "link_load.png")
    plot_png(png, 900, 400, f"""
set title '{name}: link bytes per frame (budget {rate:.0f} bytes/s)'
set xlabel 'time (s)'
set ylabel 'bytes'
set grid
plot '{csv_path}' using 'time_s':'link_bytes' with impulses lw 2 title 'bytes received'
""")


def fmt(x, digits=1):
    return "-" if x is None else f"{x:.{digits}f}"


def main():
    if len(sys.argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    out_dir = sys.argv[1]
    runs = sorted(d for d in os.listdir(out_dir)
                  if os.path.exists(os.path.join(out_dir, d, "frames.csv")))
    if not runs:
        print(f"summarize: no run with frames.csv in {out_dir}", file=sys.stderr)
        return 1
    summaries = []
    for r in runs:
        summary, rows = summarize_run(os.path.join(out_dir, r))
        summaries.append(summary)
        # A run without SNR (a latency run, --no-reference) gets only the latency plot.
        if summary["frames_with_finite_snr"]:
            plot_run(os.path.join(out_dir, r), r, rows)
        plot_latency(os.path.join(out_dir, r), r)
        if summary.get("budget_link_bytes_per_s"):
            plot_link(os.path.join(out_dir, r), r, summary["budget_link_bytes_per_s"])
    plot_comparison(out_dir, [r for r, s in zip(runs, summaries) if s["frames_with_finite_snr"]])
    with open(os.path.join(out_dir, "summary.json"), "w") as f:
        json.dump({"runs": summaries}, f, indent=2)
    lines = [f"{'run':<20} {'frames':>6} {'SNR med':>8} {'SNR min':>8} {'tris max':>8} "
             f"{'over budget':>11} {'render':>7} {'pose->frame':>11} {'update':>7} {'link KB':>8}",
             f"{'':<20} {'':>6} {'dB':>8} {'dB':>8} {'':>8} {'frames':>11} {'p99 ms':>7} "
             f"{'p99 ms':>11} {'med ms':>7}"]
    for s in summaries:
        over = s.get("frames_over_polygon_budget")
        lines.append(f"{s['name']:<20} {s['frames']:>6} {fmt(s['snr_db_median']):>8} "
                     f"{fmt(s['snr_db_min']):>8} {fmt(s['polygons_max'], 0):>8} "
                     f"{('-' if over is None else str(over)):>11} {fmt(s['render_ms_p99']):>7} "
                     f"{fmt(s['pose_to_frame_ms_p99']):>11} {fmt(s['update_latency_ms_median']):>7} "
                     f"{s['link_bytes_total'] / 1000:>8.1f}")
        if s.get("budget_link_bytes_per_s"):
            lines.append(f"{'':<20} link: worst 1 s window {s['link_bytes_max_1s_window']:.0f} bytes "
                         f"(bound rate x 1 s + burst = {s['link_bytes_1s_window_bound']:.0f}); "
                         f"mean {fmt(s['link_bytes_per_s_mean'], 0)} bytes/s "
                         f"vs budget {s['budget_link_bytes_per_s']:.0f}")
    text = "\n".join(lines) + "\n"
    with open(os.path.join(out_dir, "summary.txt"), "w") as f:
        f.write(text)
    print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main())
