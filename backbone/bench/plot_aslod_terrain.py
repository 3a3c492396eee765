#!/usr/bin/env python3
"""Plots of bench_aslod_terrain's per-region rows (docs/results/aslod-terrain.md).

Usage: backbone/bench/plot_aslod_terrain.py REGIONS_CSV OUT_PREFIX

Writes
- OUT_PREFIX-scatter.png: triangles of every rendered region against its projected area (solid
  angle of its bounding sphere from the viewer, sr), every pose; rows = budgets, columns = border
  rules, one colour per scheduler; log-log.
- OUT_PREFIX-flight.png: triangles of four regions over the flight (accuracy-curve scheduler),
  three cells of the row the viewer flies over and one far cell; rows = budgets, columns =
  border rules; the projected area dotted on the right axis. A region the plan does not render
  (culled or dropped) is drawn at 0 triangles.
Needs matplotlib (Debian: python3-matplotlib; run with /usr/bin/python3 if another python3 comes
first on PATH).
"""
import csv
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SCHEDULER_COLOURS = {"accuracy-curve": "tab:blue", "greedy-fs93": "tab:orange",
                     "aslod": "tab:green"}
FLIGHT_CELLS = [(0, 2), (2, 2), (4, 2), (3, 5)]  # (i, j): column, row
FLIGHT_COLOURS = ["tab:blue", "tab:orange", "tab:green", "tab:red"]


def load(path):
    rows = []
    with open(path, newline="") as f:
        for r in csv.DictReader(f):
            rows.append({
                "rule": r["rule"], "scheduler": r["scheduler"], "budget": float(r["budget"]),
                "pose": int(r["pose"]), "x": float(r["x"]), "cell": (int(r["cell_i"]),
                                                                    int(r["cell_j"])),
                "rendered": r["rendered"] == "1", "triangles": float(r["triangles"]),
                "area": float(r["projected_area_sr"]),
            })
    return rows


def scatter(rows, out):
    budgets = sorted({r["budget"] for r in rows}, reverse=True)
    rules = sorted({r["rule"] for r in rows})
    fig, axes = plt.subplots(len(budgets), len(rules), figsize=(5.2 * len(rules),
                                                                4.2 * len(budgets)),
                             squeeze=False)
    for bi, budget in enumerate(budgets):
        for ri, rule in enumerate(rules):
            ax = axes[bi][ri]
            points = defaultdict(lambda: ([], []))
            for r in rows:
                if r["budget"] == budget and r["rule"] == rule and r["rendered"]:
                    xs, ys = points[r["scheduler"]]
                    xs.append(r["area"])
                    ys.append(max(r["triangles"], 0.5))
            for name, (xs, ys) in sorted(points.items()):
                ax.scatter(xs, ys, s=5, alpha=0.35, color=SCHEDULER_COLOURS.get(name, "grey"),
                           label=f"{name} ({len(xs)})")
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_title(f"budget {budget:.0f}, border rule {rule}")
            ax.set_xlabel("projected area of the region's bounding sphere (sr)")
            ax.set_ylabel("triangles of the region")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=8, markerscale=3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def flight(rows, out):
    budgets = sorted({r["budget"] for r in rows}, reverse=True)
    rules = sorted({r["rule"] for r in rows})
    fig, axes = plt.subplots(len(budgets), len(rules), figsize=(5.6 * len(rules),
                                                                4.0 * len(budgets)),
                             squeeze=False)
    for bi, budget in enumerate(budgets):
        for ri, rule in enumerate(rules):
            ax = axes[bi][ri]
            twin = ax.twinx()
            for cell, colour in zip(FLIGHT_CELLS, FLIGHT_COLOURS):
                series = sorted((r["x"], r["triangles"] if r["rendered"] else 0.0, r["area"])
                                for r in rows
                                if r["budget"] == budget and r["rule"] == rule and
                                r["scheduler"] == "accuracy-curve" and r["cell"] == cell)
                if not series:
                    continue
                xs = [s[0] for s in series]
                ax.plot(xs, [s[1] for s in series], color=colour, lw=1.4,
                        label=f"cell ({cell[0]}, {cell[1]}) triangles")
                twin.plot(xs, [s[2] for s in series], color=colour, lw=0.9, ls=":")
            ax.set_title(f"accuracy-curve, budget {budget:.0f}, border rule {rule}")
            ax.set_xlabel("viewer x (m); the terrain spans 0..2600")
            ax.set_ylabel("triangles (solid)")
            twin.set_ylabel("projected area, sr (dotted)")
            twin.set_yscale("log")
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize=7, loc="upper left")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    rows = load(sys.argv[1])
    scatter(rows, sys.argv[2] + "-scatter.png")
    flight(rows, sys.argv[2] + "-flight.png")


if __name__ == "__main__":
    main()
