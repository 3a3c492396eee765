#!/usr/bin/env python3
"""Run time against error, one panel per model, from bench_simplify's simplify.csv.

Usage: simplifier/bench/plot_simplify.py CSV OUT_PREFIX

Writes OUT_PREFIX-max.png and OUT_PREFIX-mean.png (symmetric Hausdorff max / mean error in % of
the bbox diagonal against thread CPU ms, both log scales). Per model and ratio (50/10/1%) four
methods: thinlod build + extract (a whole progressive mesh built, then that level extracted: the
cost of the first level), thinlod extract (every later level), meshoptimizer and OpenMesh's
decimater (one call per level). Errors below 1e-4 % are drawn at 1e-4 % (float noise; the
results page says so). Only the Python standard library and gnuplot are used (as
deploy/summarize.py).
"""
import csv
import math
import os
import subprocess
import sys
import tempfile

FLOOR = 1e-4  # % of the diagonal
METHODS = [  # (key, title, gnuplot style)
    ("build+extract", "thinlod build + extract", "lc rgb '#1f77b4' pt 7"),
    ("thinlod_extract", "thinlod extract", "lc rgb '#2ca02c' pt 5"),
    ("meshopt", "meshoptimizer", "lc rgb '#d62728' pt 9"),
    ("openmesh", "OpenMesh decimater", "lc rgb '#9467bd' pt 11"),
]


def read(path):
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    models = []
    data = {}  # model -> method -> [(ratio, ms, max, mean)]
    build = {}
    for r in rows:
        model = r["model"]
        if model not in data:
            models.append(model)
            data[model] = {}
        method = r["method"]
        ms = float(r["time_ms"])
        if method == "thinlod_build":
            build[model] = ms
            continue
        ratio = float(r["ratio"])
        err_max = max(float(r["max_error_pct_diag"]), FLOOR)
        err_mean = max(float(r["mean_error_pct_diag"]), FLOOR)
        data[model].setdefault(method, []).append((ratio, ms, err_max, err_mean))
    for model in models:
        ours = data[model].get("thinlod_extract", [])
        if model in build:
            data[model]["build+extract"] = [
                (ratio, build[model] + ms, e1, e2) for ratio, ms, e1, e2 in ours
            ]
    return models, data


def plot(models, data, png, column, label, tmp):
    cols = 4
    rows = math.ceil(len(models) / cols)
    script = [
        "set terminal pngcairo size %d,%d noenhanced font ',9'" % (330 * cols, 280 * rows),
        "set output '%s'" % png,
        "set multiplot layout %d,%d title 'bench_simplify: %s against thread CPU time "
        "(points: 50%%, 10%%, 1%% of the triangles)'" % (rows, cols, label),
        "set logscale xy",
        "set format x '%g'",
        "set format y '%g'",
        "set grid",
        "set key top left opaque font ',7' samplen 1",
        "set xlabel 'CPU ms'",
        "set ylabel '%s (%% diag)'" % label,
    ]
    for i, model in enumerate(models):
        plots = []
        for key, title, style in METHODS:
            points = sorted(data[model].get(key, []), reverse=True)
            if not points:
                continue
            path = os.path.join(tmp, "%d-%s.dat" % (i, key))
            with open(path, "w") as f:
                for ratio, ms, e_max, e_mean in points:
                    f.write("%g %g %g\n" % (ms, e_max if column == "max" else e_mean, ratio))
            plots.append("'%s' using 1:2 with linespoints %s ps 0.8 title '%s'" % (path, style, title))
        script.append("set title '%s'" % model)
        script.append("unset key" if i else "set key")
        script.append("plot " + ", ".join(plots))
    script.append("unset multiplot")
    subprocess.run(["gnuplot"], input="\n".join(script).encode(), check=True)


def main():
    if len(sys.argv) != 3:
        print(__doc__, file=sys.stderr)
        return 2
    models, data = read(sys.argv[1])
    with tempfile.TemporaryDirectory() as tmp:
        plot(models, data, sys.argv[2] + "-max.png", "max", "max error", tmp)
        plot(models, data, sys.argv[2] + "-mean.png", "mean", "mean error", tmp)
    print("wrote %s-max.png, %s-mean.png" % (sys.argv[2], sys.argv[2]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
