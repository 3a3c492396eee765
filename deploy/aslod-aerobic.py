#!/usr/bin/env python3
"""The ASLOD "aerobic class" numbers (issue 18, docs/results/aslod.md) from deploy/compare
results folders of the on-request case aerobic-class:

  deploy/compare --no-build --cases aerobic-class --out DIR        (every scheduler, live)
  deploy/aslod-aerobic.py DIR [DIR ...] [--img-dir docs/results/img]

Per run (frames.csv, objects.csv, decisions.csv of thinlod-frontend / thinlod-backbone):
triangles per frame (and frames over the budget), frame time (render_ms: mean, standard
deviation, coefficient of variation over every frame and over the frames without uploads),
deformed vertices against the full figures' vertices, link bytes per frame split into bone
poses (pose_bytes) and the rest, SNR median / p10 / min (nearest rank, as
deploy/workbench_report.py). Per scheduler of the first folder: each figure's share of the
triangles in four 3 s windows, and with --img-dir the plots aslod-aerobic-share.png (triangles
per figure per frame, stacked), aslod-aerobic-frames.png (frame time, deformed vertices, link
bytes of the accuracy-curve run) and aslod-aerobic-snr.png (SNR per frame, every scheduler).
Prints Markdown. Standard library, plus matplotlib for the plots.
"""
import argparse
import csv
import json
import math
import os
import statistics
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from workbench_report import nearest_rank, minimum, number  # noqa: E402

# Testwuson.X as imported skinned: 3205 vertices (docs/animation.md, "Served"); the full mesh
# the reference deforms. The scene's three figures, told apart by their x in objects.csv.
FULL_VERTICES = 3205
FIGURES = {-3.0: "left (Run)", 0.0: "middle (Walk)", 3.0: "right (Run)"}
WINDOWS = [(0.0, 3.0), (3.0, 6.0), (6.0, 9.0), (9.0, 12.0)]


def read_rows(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def cv_stats(values):
    """(mean, population standard deviation, coefficient of variation) of finite values."""
    values = [v for v in values if math.isfinite(v)]
    if len(values) < 2:
        return math.nan, math.nan, math.nan
    mean = statistics.fmean(values)
    sd = statistics.pstdev(values)
    return mean, sd, sd / mean if mean > 0 else math.nan


def figure_of(row):
    x = round(number(row["x"]), 3)
    return FIGURES.get(x, f"object {row['object']} at x {x:g}")


def per_object(objects_rows):
    """{frame: {figure: triangles}} of the held objects that have a pose (drawn)."""
    frames = {}
    for r in objects_rows:
        held = frames.setdefault(int(r["frame"]), {})
        if r["posed"] == "1" or r["skinned"] == "0":
            held[figure_of(r)] = int(r["triangles"])
    return frames


def run_stats(run_dir):
    frames = read_rows(os.path.join(run_dir, "frames.csv"))
    objects = per_object(read_rows(os.path.join(run_dir, "objects.csv")))
    budget = run_meta(run_dir)["budget_polygons"]
    col = lambda key: [number(r[key]) for r in frames]
    tris, render = col("polygons"), col("render_ms")
    steady = [number(r["render_ms"]) for r in frames
              if number(r["uploaded_bytes"]) == 0 and number(r["skinned_objects"]) > 0]
    link, pose = col("link_bytes"), col("pose_bytes")
    deformed, skinned = col("deformed_vertices"), col("skinned_objects")
    snr = col("snr_db")
    # objects.csv's drawn vertices agree with frames.csv's deformed_vertices (a check).
    mismatched = 0
    vertices_by_frame = {}
    for r in read_rows(os.path.join(run_dir, "objects.csv")):
        if r["skinned"] == "1" and r["posed"] == "1":
            f = int(r["frame"])
            vertices_by_frame[f] = vertices_by_frame.get(f, 0) + int(r["vertices"])
    for r in frames:
        if vertices_by_frame.get(int(r["frame"]), 0) != int(r["deformed_vertices"]):
            mismatched += 1
    # A frame shows its own pose's bone poses when the update answering that pose became
    # visible in it (update_latency_ms under one 100 ms slot); otherwise it draws an older pose
    # (a late update, or none this frame) against a reference at its own time. From frame 3 on.
    def own_pose(r):
        return number(r["update_latency_ms"]) < 100.0
    stale = [number(r["snr_db"]) for r in frames[3:] if not own_pose(r)]
    fresh = [number(r["snr_db"]) for r in frames[3:] if own_pose(r)]
    mean, sd, cv = cv_stats(render)
    smean, ssd, scv = cv_stats(steady)
    # A robust spread of the same frames: median absolute deviation over the median.
    smed = statistics.median(steady) if steady else math.nan
    smad = statistics.median([abs(v - smed) for v in steady]) / smed if steady else math.nan
    drawn3 = [d for d, s in zip(deformed, skinned) if s == 3]
    return {
        "frames": len(frames), "budget": budget,
        "tris_min": min(tris), "tris_med": nearest_rank(tris, 0.5), "tris_max": max(tris),
        "over_budget": sum(1 for t in tris if t > budget),
        "frames_all_three": sum(1 for s in skinned if s == 3),
        "render_mean": mean, "render_sd": sd, "render_cv": cv,
        "steady_frames": len(steady), "steady_mean": smean, "steady_cv": scv, "steady_mad": smad,
        "render_max": max(render),
        "deformed_med": nearest_rank(deformed, 0.5), "deformed_min3": min(drawn3) if drawn3 else None,
        "deformed_max": max(deformed), "full_vertices": 3 * FULL_VERTICES,
        "vertex_mismatch_frames": mismatched,
        "link_total": sum(link), "link_med": nearest_rank(link, 0.5), "link_max": max(link),
        "pose_total": sum(pose), "pose_med": nearest_rank(pose, 0.5),
        "frames_without_pose": sum(1 for p in pose if p == 0),
        "frames_older_pose": len(stale),
        "snr_med_stale": nearest_rank(stale, 0.5), "snr_med_fresh": nearest_rank(fresh, 0.5),
        "tris_cv": cv_stats([t for t, s in zip(tris, skinned) if s == 3])[2],
        "snr_med": nearest_rank(snr, 0.5), "snr_p10": nearest_rank(snr, 0.1), "snr_min": minimum(snr),
        "objects": objects, "rows": frames,
    }


def shares(stats):
    """Per 3 s window: each figure's mean triangles and share of the window's triangles."""
    out = []
    times = {int(r["frame"]): number(r["time_s"]) for r in stats["rows"]}
    for lo, hi in WINDOWS:
        total, per = 0, {}
        for f, held in stats["objects"].items():
            if lo <= times.get(f, -1) < hi:
                for name, t in held.items():
                    per[name] = per.get(name, 0) + t
                    total += t
        n = sum(1 for f in stats["objects"] if lo <= times.get(f, -1) < hi)
        out.append((lo, hi, {k: (v / n, v / total) for k, v in per.items()} if total else {}))
    return out


def fmt(x, digits=1):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "-"
    if isinstance(x, float) and math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return f"{x:,.{digits}f}" if digits else f"{int(round(x)):,}"


def run_meta(run_dir):
    """deploy/compare's run.json (scheduler, budget, settings), or the folder name's parts
    (aerobic-class-SCHEDULER-BUDGET) for a hand-made run folder without one."""
    path = os.path.join(run_dir, "run.json")
    if os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    scheduler, budget = os.path.basename(run_dir.rstrip("/"))[len("aerobic-class-"):].rsplit("-", 1)
    return {"scheduler": scheduler, "budget_polygons": int(budget)}


def runs_of(root):
    found = {}
    for d in sorted(os.listdir(root)):
        path = os.path.join(root, d)
        if d.startswith("aerobic-class-") and os.path.exists(os.path.join(path, "objects.csv")):
            found[run_meta(path)["scheduler"]] = path
    return found


def plots(img_dir, runs):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    names = list(FIGURES.values())
    shown = [s for s in ("curves", "greedy", "aslod", "active-set") if s in runs]
    fig, axes = plt.subplots(len(shown), 1, figsize=(8, 2.3 * len(shown)), sharex=True)
    for ax, s in zip(axes if len(shown) > 1 else [axes], shown):
        st = runs[s]
        times = [number(r["time_s"]) for r in st["rows"]]
        series = [[st["objects"].get(int(r["frame"]), {}).get(n, 0) for r in st["rows"]]
                  for n in names]
        ax.stackplot(times, *series, labels=names, step="post")
        ax.axhline(st["budget"], color="k", lw=0.8, ls="--", label="budget")
        ax.set_ylabel("triangles")
        ax.set_title(f"{s}: triangles per figure (drawn, stacked)", fontsize=9)
        ax.set_ylim(0, st["budget"] * 1.1)
    (axes[0] if len(shown) > 1 else axes).legend(fontsize=7, loc="lower right", ncol=4)
    (axes[-1] if len(shown) > 1 else axes).set_xlabel("trace time (s)")
    fig.tight_layout()
    fig.savefig(os.path.join(img_dir, "aslod-aerobic-share.png"), dpi=90)
    plt.close(fig)

    st = runs["curves"]
    times = [number(r["time_s"]) for r in st["rows"]]
    col = lambda key: [number(r[key]) for r in st["rows"]]
    fig, axes = plt.subplots(3, 1, figsize=(8, 6.5), sharex=True)
    axes[0].plot(times, col("render_ms"), lw=0.9)
    axes[0].set_ylabel("render_ms")
    axes[0].set_title("curves: frame time (renderFrame wall time, uploads included)", fontsize=9)
    axes[1].plot(times, col("deformed_vertices"), label="deformed (held levels)", lw=0.9)
    axes[1].axhline(3 * FULL_VERTICES, color="k", ls="--", lw=0.8, label="3 full figures")
    axes[1].set_ylabel("vertices")
    axes[1].set_ylim(0, 3 * FULL_VERTICES * 1.1)
    axes[1].legend(fontsize=7)
    axes[2].bar(times, col("link_bytes"), width=0.09, label="link bytes", color="C1")
    axes[2].bar(times, col("pose_bytes"), width=0.09, label="of which bone poses", color="C0")
    axes[2].set_yscale("symlog", linthresh=1000)
    axes[2].set_ylabel("bytes / frame")
    axes[2].set_xlabel("trace time (s)")
    axes[2].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(img_dir, "aslod-aerobic-frames.png"), dpi=90)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(8, 3))
    for s, st in runs.items():
        snr = [max(number(r["snr_db"]), -5.0) for r in st["rows"]]
        ax.plot([number(r["time_s"]) for r in st["rows"]], snr, lw=0.9, label=s)
    ax.set_ylabel("SNR dB (-inf drawn at -5)")
    ax.set_xlabel("trace time (s)")
    ax.set_title("aerobic class, live, budget 5,000: SNR per shown frame", fontsize=9)
    ax.legend(fontsize=7, ncol=3)
    fig.tight_layout()
    fig.savefig(os.path.join(img_dir, "aslod-aerobic-snr.png"), dpi=90)
    plt.close(fig)


def main(argv):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("roots", nargs="+", help="deploy/compare --out folders")
    parser.add_argument("--img-dir", help="write the plots there (from the first folder)")
    args = parser.parse_args(argv)
    all_runs = [(root, {s: run_stats(p) for s, p in runs_of(root).items()}) for root in args.roots]
    print("| folder | scheduler | frames | tris min / med / max | over budget | tris CV (frames with 3 "
          "drawn: n) | deformed vertices med (max) of 9,615 | link B/frame med (max) | pose B/frame "
          "med | pose share of link bytes |")
    print("|" + " --- |" * 10)
    for root, runs in all_runs:
        for s, st in runs.items():
            print(f"| {os.path.basename(root.rstrip('/'))} | {s} | {st['frames']} | "
                  f"{fmt(st['tris_min'], 0)} / {fmt(st['tris_med'], 0)} / {fmt(st['tris_max'], 0)} | "
                  f"{st['over_budget']} | {fmt(100 * st['tris_cv'])} % ({st['frames_all_three']}) | "
                  f"{fmt(st['deformed_med'], 0)} ({fmt(st['deformed_max'], 0)}) | "
                  f"{fmt(st['link_med'], 0)} ({fmt(st['link_max'], 0)}) | {fmt(st['pose_med'], 0)} | "
                  f"{fmt(100 * st['pose_total'] / st['link_total'])} % |")
            if st["vertex_mismatch_frames"]:
                print(f"<!-- {s}: objects.csv vertices differ from deformed_vertices in "
                      f"{st['vertex_mismatch_frames']} frames -->")
    print()
    print("| folder | scheduler | render ms mean / sd / max | CV all frames | CV frames without "
          "uploads (n) | MAD / median, same frames | frames receiving no pose | frames 3+ drawn with an older pose | SNR med / p10 / "
          "min dB | SNR med, frames 3+ with their own pose / an older one |")
    print("|" + " --- |" * 10)
    for root, runs in all_runs:
        for s, st in runs.items():
            print(f"| {os.path.basename(root.rstrip('/'))} | {s} | "
                  f"{fmt(st['render_mean'], 2)} / {fmt(st['render_sd'], 2)} / {fmt(st['render_max'], 1)} | "
                  f"{fmt(100 * st['render_cv'])} % | {fmt(100 * st['steady_cv'])} % "
                  f"({st['steady_frames']}) | {fmt(100 * st['steady_mad'])} % | "
                  f"{st['frames_without_pose']} | "
                  f"{st['frames_older_pose']} | "
                  f"{fmt(st['snr_med'])} / {fmt(st['snr_p10'])} / {fmt(st['snr_min'])} | "
                  f"{fmt(st['snr_med_fresh'])} / {fmt(st['snr_med_stale'])} |")
    root, runs = all_runs[0]
    print()
    print(f"Per-figure triangles (mean per frame) and share, {os.path.basename(root.rstrip('/'))}:")
    print()
    print("| scheduler | window (s) | " + " | ".join(FIGURES.values()) + " |")
    print("|" + " --- |" * (2 + len(FIGURES)))
    for s, st in runs.items():
        for lo, hi, per in shares(st):
            cells = [f"{fmt(per[n][0], 0)} ({fmt(100 * per[n][1], 0)} %)" if n in per else "0"
                     for n in FIGURES.values()]
            print(f"| {s} | {lo:g}-{hi:g} | " + " | ".join(cells) + " |")
    if args.img_dir:
        plots(args.img_dir, runs)
        print(f"\nplots in {args.img_dir}: aslod-aerobic-share.png, aslod-aerobic-frames.png, "
              "aslod-aerobic-snr.png", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
