#!/usr/bin/env python3
"""Summarises a deploy/compare results folder: per-run metrics (metrics.json, metrics.csv), one
table across runs (table.md, table.csv, table.json), a gnuplot plot of SNR per frame for every
scheduler of each case (snr-<case>.png) and a self-contained results page (index.html: table,
plots, frame / reference / difference images inlined as base64, the settings of every run).

Usage: deploy/workbench_report.py RESULTS_DIR [--doc FILE.md] [--from-time SECONDS]
  --from-time leaves out every frame whose time_s is below SECONDS (a trace's warm-up hold, e.g.
  deploy/data/parts-fly-hold.trace's 25 s) from every metric, plot and page of this report.
  --doc replaces the part of FILE.md between the lines "<!-- workbench:begin -->" and
  "<!-- workbench:end -->" with this folder's table, settings and images (the images are copied
  to img/ beside FILE.md as workbench-*.png); deploy/compare --write-doc uses it for
  docs/results/workbench.md.

Every run folder holds run.json (deploy/compare), frames.csv and frontend-summary.json
(thinlod-frontend), decisions.csv (thinlod-backbone) and frames/ (PNG dumps). Standard library
and gnuplot only. The metric functions are pure and tested by tests/workbench/.
"""
import base64
import csv
import html
import json
import math
import os
import shutil
import subprocess
import sys

# Columns of the table: (key, Markdown header, digits or None for integers/text).
COLUMNS = [
    ("case", "case", None), ("scheduler", "scheduler", None), ("budget_polygons", "budget", None),
    ("mode", "mode", None), ("frames", "frames", None),
    ("snr_db_median", "SNR med dB", 1), ("snr_db_p10", "SNR p10", 1), ("snr_db_min", "SNR min", 1),
    ("psnr_db_median", "PSNR med dB", 1), ("psnr_db_p10", "PSNR p10", 1),
    ("psnr_db_min", "PSNR min", 1),
    ("blank_frames", "blank", None), ("incomplete_frames", "incomplete", None),
    ("frames_over_budget", "over budget", None), ("polygons_max", "tris max", None),
    ("units_max", "units max", 1), ("budget_used_pct", "used %", 0),
    ("link_kb_total", "link KB", 1), ("link_kb_worst_1s", "worst 1 s KB", 1),
    ("simplifier_requests", "requests", None),
    ("update_latency_ms_median", "update med ms", 0), ("update_latency_ms_p99", "update p99 ms", 0),
    ("pose_to_frame_ms_p99", "pose->frame p99 ms", 1),
    ("own_answer_pct", "own answer %", 0),
    ("first_complete_ms", "first complete ms", 0),
]


def number(text):
    """A CSV field as float: '' -> nan, 'inf' / '-inf' -> infinities."""
    try:
        return float(text)
    except (TypeError, ValueError):
        return math.nan


def nearest_rank(values, q):
    """The q-quantile (0 < q <= 1) by nearest rank over the non-NaN values (infinities count,
    as in the frontend's summary): element ceil(q n) - 1 of the sorted values; None if empty."""
    values = sorted(v for v in values if not math.isnan(v))
    if not values:
        return None
    return values[max(0, math.ceil(q * len(values)) - 1)]


def minimum(values):
    values = [v for v in values if not math.isnan(v)]
    return min(values) if values else None


def worst_window(times, amounts, window=1.0):
    """Largest sum of `amounts` over any half-open window [t, t + window) of the `times`."""
    best, j, total = 0.0, 0, 0.0
    pairs = sorted(zip(times, amounts))
    for i, (t, a) in enumerate(pairs):
        total += a
        while pairs[j][0] <= t - window:
            total -= pairs[j][1]
            j += 1
        best = max(best, total)
    return best


def frame_units(row):
    """A frame's primitive units, what the budget counts: its "units" column (triangles + points /
    kappa, thinlod-frontend) when it holds a number; its triangles ("polygons") when it drew no
    points or frames.csv predates the column; NaN when points were drawn at an unknown kappa."""
    units = number(row.get("units"))
    if not math.isnan(units):
        return units
    points = number(row.get("points"))
    if math.isnan(points) or points == 0:
        return number(row.get("polygons"))
    return math.nan


def first_complete(rows):
    """(frame, shown_at_ms) of the first frame that shows every visible object (at least one
    visible, none missing), or (None, None)."""
    for r in rows:
        visible, missing = number(r.get("visible_objects")), number(r.get("missing_objects"))
        if visible >= 1 and missing == 0:
            return int(number(r["frame"])), number(r.get("shown_at_ms"))
    return None, None


def budget_used_pct(rows, units, complete_frame, budget):
    """100 x the mean primitive units of the frames from `complete_frame` on (every frame when
    it is None) over `budget`; None without a budget or a frame of known units."""
    if not budget:
        return None
    start = 0
    if complete_frame is not None:
        start = next((i for i, r in enumerate(rows) if int(number(r["frame"])) == complete_frame), 0)
    known = [u for u in units[start:] if not math.isnan(u)]
    return 100.0 * sum(known) / len(known) / budget if known else None


def jsonable(x):
    """None for NaN, strings for infinities (JSON has neither)."""
    if isinstance(x, float):
        if math.isnan(x):
            return None
        if math.isinf(x):
            return "inf" if x > 0 else "-inf"
    return x


def read_rows(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def run_metrics(run_dir, from_time=None):
    """Metrics of one run folder; with from_time, of its frames with time_s >= from_time."""
    meta = json.load(open(os.path.join(run_dir, "run.json")))
    rows = read_rows(os.path.join(run_dir, "frames.csv"))
    if from_time is not None:
        rows = [r for r in rows if number(r.get("time_s")) >= from_time]
    decisions = read_rows(os.path.join(run_dir, "decisions.csv"))
    summary_path = os.path.join(run_dir, "frontend-summary.json")
    summary = json.load(open(summary_path)) if os.path.exists(summary_path) else {}
    col = lambda key: [number(r.get(key)) for r in rows]
    snr, psnr, polygons = col("snr_db"), col("psnr_db"), col("polygons")
    units = [frame_units(r) for r in rows]
    known_units = [u for u in units if not math.isnan(u)]
    points = [p for p in col("points") if not math.isnan(p)]
    budget = meta.get("budget_polygons")
    frame, complete_ms = first_complete(rows)
    m = {
        "name": meta["name"], "case": meta.get("case"), "scheduler": meta.get("scheduler"),
        "budget_polygons": budget,
        "mode": meta.get("mode") + (f" +{meta['answer_wait_ms']} ms" if meta.get("answer_wait_ms")
                                    else "") + (f" +link {meta['budget_link_bytes_per_s']} B/s"
                                                if meta.get("budget_link_bytes_per_s") else "")
        if meta.get("mode") else None,
        "reference_mode": summary.get("reference_mode"),
        "frames": len(rows), "frames_scored": sum(1 for s in snr if not math.isnan(s)),
        "frames_not_kept": summary.get("frames_not_kept"),
        "snr_db_median": nearest_rank(snr, 0.5), "snr_db_p10": nearest_rank(snr, 0.1),
        "snr_db_min": minimum(snr),
        "psnr_db_median": nearest_rank(psnr, 0.5), "psnr_db_p10": nearest_rank(psnr, 0.1),
        "psnr_db_min": minimum(psnr),
        "blank_frames": sum(1 for r in rows if r.get("blank") == "1"),
        "incomplete_frames": sum(1 for r in rows if number(r.get("missing_objects")) > 0),
        "polygons_max": int(max(polygons)) if polygons else None,
        "units_max": max(known_units) if known_units else None,
        # Mean units at the frontend over the budget, from the first complete frame on (before
        # it the objects are still arriving), or over every frame when none is complete.
        "budget_used_pct": budget_used_pct(rows, units, frame, budget),
        # Over the budget in units (triangles + points / kappa); frames whose units are unknown
        # (points at an unknown kappa) are counted apart, never as within it.
        "frames_over_budget": sum(1 for u in known_units if budget and u > budget),
        "frames_units_unknown": len(units) - len(known_units),
        "points_max": int(max(points)) if points else None,
        "from_time_s": from_time,
        "link_kb_total": sum(x for x in col("link_bytes") if not math.isnan(x)) / 1000.0,
        "link_kb_worst_1s": worst_window(col("time_s"), [0 if math.isnan(x) else x
                                                         for x in col("link_bytes")]) / 1000.0,
        "simplifier_requests": int(sum(x for x in (number(d.get("requests")) for d in decisions)
                                       if not math.isnan(x))),
        "plans": len(decisions),
        "update_latency_ms_median": nearest_rank(col("update_latency_ms"), 0.5),
        "update_latency_ms_p99": nearest_rank(col("update_latency_ms"), 0.99),
        "pose_to_frame_ms_p99": nearest_rank(col("pose_to_frame_ms"), 0.99),
        # Frames drawn with the answer to their own pose (frames.csv own_answer; None for runs
        # written before the column existed).
        "own_answer_pct": (100.0 * sum(1 for r in rows if r.get("own_answer") == "1") / len(rows)
                           if rows and "own_answer" in rows[0] else None),
        "first_complete_frame": frame,
        "first_complete_ms": complete_ms,
        "wall_s": meta.get("wall_s"), "exit_code": meta.get("exit_code"),
    }
    return {k: jsonable(v) for k, v in m.items()}, meta, rows


def cell(value, digits):
    if value is None:
        return "-"
    if isinstance(value, str):
        return value
    if digits is None:
        return str(value)
    return f"{value:.{digits}f}"


def write_tables(out_dir, metrics):
    with open(os.path.join(out_dir, "table.json"), "w") as f:
        json.dump({"runs": metrics}, f, indent=2)
    with open(os.path.join(out_dir, "table.csv"), "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow([k for k, _, _ in COLUMNS])
        for m in metrics:
            writer.writerow(["" if m.get(k) is None else m.get(k) for k, _, _ in COLUMNS])
    best = best_median_per_case(metrics)
    lines = ["| " + " | ".join(h for _, h, _ in COLUMNS) + " |",
             "| " + " | ".join("---" for _ in COLUMNS) + " |"]
    for m in metrics:
        cells = [cell(m.get(k), d) for k, _, d in COLUMNS]
        if best.get(m["case"]) == m["name"]:
            i = [k for k, _, _ in COLUMNS].index("snr_db_median")
            cells[i] = f"**{cells[i]}**"
        lines.append("| " + " | ".join(cells) + " |")
    text = "\n".join(lines) + "\n"
    with open(os.path.join(out_dir, "table.md"), "w") as f:
        f.write(text)
    return text


def best_median_per_case(metrics):
    """case -> name of the run with the highest median SNR ('inf' counts as highest)."""
    best = {}
    for m in metrics:
        v = m.get("snr_db_median")
        v = math.inf if v == "inf" else -math.inf if v in (None, "-inf") else v
        if m["case"] not in best or v > best[m["case"]][0]:
            best[m["case"]] = (v, m["name"])
    return {c: n for c, (_, n) in best.items()}


def plot_case(out_dir, case, runs):
    """SNR per frame of every run of `case`; infinities drawn at the plot's edges."""
    if shutil.which("gnuplot") is None:
        print("workbench_report: gnuplot not found; plots skipped", file=sys.stderr)
        return None
    lo, hi = -20.0, 60.0
    parts = []
    for name, rows in runs:
        dat = os.path.join(out_dir, name, "snr_plot.dat")
        with open(dat, "w") as f:
            for r in rows:
                s = number(r.get("snr_db"))
                if not math.isnan(s):
                    f.write(f"{r['frame']} {min(max(s, lo), hi):.4f}\n")
        parts.append(f"'{dat}' using 1:2 with linespoints pt 7 ps 0.3 title '{name}'")
    png = os.path.join(out_dir, f"snr-{case}.png")
    script = f"""
set terminal pngcairo size 900,420 noenhanced
set output '{png}'
set title '{case}: SNR of each shown frame against its own pose (values beyond [{lo:g}, {hi:g}] and infinities drawn at the edges)'
set xlabel 'frame'
set ylabel 'SNR (dB)'
set yrange [{lo}:{hi}]
set grid
set key outside bottom center horizontal
plot {', '.join(parts)}
"""
    subprocess.run(["gnuplot"], input=script.encode(), check=True)
    return png


def dumped_frames(run_dir):
    frames_dir = os.path.join(run_dir, "frames")
    if not os.path.isdir(frames_dir):
        return set()
    return {int(f[6:10]) for f in os.listdir(frames_dir)
            if f.startswith("frame_") and f.endswith(".png")}


def pick_frame(run_dirs):
    """A dumped frame number common to all runs of a case, near the middle of the replay."""
    common = None
    for d in run_dirs:
        common = dumped_frames(d) if common is None else common & dumped_frames(d)
    if not common:
        return None
    ordered = sorted(common)
    return ordered[len(ordered) // 2]


def data_uri(path):
    with open(path, "rb") as f:
        return "data:image/png;base64," + base64.b64encode(f.read()).decode("ascii")


def write_page(out_dir, settings, metrics, metas, rows_by_run, plots):
    e = html.escape
    by_case = {}
    for m in metrics:
        by_case.setdefault(m["case"], []).append(m)
    best = best_median_per_case(metrics)
    head = "".join(f"<th>{e(h)}</th>" for _, h, _ in COLUMNS)
    body = []
    for m in metrics:
        cells = "".join(
            f"<td class=\"{'best' if k == 'snr_db_median' and best.get(m['case']) == m['name'] else ''}\">"
            f"{e(cell(m.get(k), d))}</td>" for k, _, d in COLUMNS)
        body.append(f"<tr>{cells}</tr>")
    sections = []
    for case, runs in by_case.items():
        run_dirs = [os.path.join(out_dir, r["name"]) for r in runs]
        frame = pick_frame(run_dirs)
        parts = [f"<h2 id=\"{e(case)}\">{e(case)}</h2>"]
        if plots.get(case):
            parts.append(f"<img class=\"plot\" alt=\"SNR per frame, {e(case)}\" "
                         f"src=\"{data_uri(plots[case])}\">")
        if frame is not None:
            parts.append(f"<p>Frame {frame} (the same pose in every run): what each scheduler "
                         f"showed, the full-quality reference of that pose, their difference.</p>")
            for r, d in zip(runs, run_dirs):
                row = next((x for x in rows_by_run[r["name"]] if x["frame"] == str(frame)), {})
                caption = (f"{r['scheduler']}: SNR {e(row.get('snr_db', '-') or '-')} dB, "
                           f"{e(row.get('polygons', '-'))} triangles, "
                           f"{e(row.get('missing_objects', '-') or '-')} visible objects missing")
                figs = []
                for kind in ("frame", "reference", "difference"):
                    p = os.path.join(d, "frames", f"{kind}_{frame:04d}.png")
                    if os.path.exists(p):
                        figs.append(f"<figure><img alt=\"{e(r['name'])} {kind}\" "
                                    f"src=\"{data_uri(p)}\"><figcaption>{e(r['name'])}: {kind}"
                                    f"</figcaption></figure>")
                parts.append(f"<p>{caption}</p><div class=\"row\">{''.join(figs)}</div>")
        sections.append("\n".join(parts))
    run_settings = "".join(
        f"<tr><td>{e(m['name'])}</td><td><code>{e(m.get('backbone_args', ''))}</code></td>"
        f"<td><code>{e(m.get('frontend_args', ''))}</code></td><td>{e(str(m.get('wall_s')))}"
        f"</td></tr>" for m in metas)
    page = f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>thinlod workbench</title>
<style>
body {{ font-family: sans-serif; margin: 1.5em; background: #fafafa; color: #222; }}
table {{ border-collapse: collapse; font-size: 12px; }}
td, th {{ border: 1px solid #bbb; padding: 2px 6px; text-align: right; }}
td.best {{ font-weight: bold; background: #e6f4e6; }}
.row {{ display: flex; gap: 8px; flex-wrap: wrap; }}
figure {{ margin: 0; }} figure img {{ width: 320px; border: 1px solid #888; }}
img.plot {{ max-width: 900px; }}
code {{ font-size: 11px; }}
</style></head><body>
<h1>thinlod evaluation workbench</h1>
<p>Mode <b>{e(settings.get('mode', '?'))}</b>: {e(MODE_TEXT.get(settings.get('mode'), ''))}
Command <code>{e(settings.get('command', ''))}</code>, started {e(settings.get('started', '?'))},
{e(str(settings.get('runs', len(metrics))))} runs in {e(str(settings.get('wall_s', '?')))} s.
The best median SNR of each case is highlighted.</p>
<table><tr>{head}</tr>
{''.join(body)}
</table>
{''.join(sections)}
<h2>Settings of every run</h2>
<table><tr><th>run</th><th>backbone</th><th>frontend</th><th>wall s</th></tr>{run_settings}</table>
{IMAGE_CHECK}
</body></html>
"""
    path = os.path.join(out_dir, "index.html")
    with open(path, "w") as f:
        f.write(page)
    return path


# Reports every image that did not decode on the console, where the page test looks.
IMAGE_CHECK = """<script>
window.addEventListener("load", () => {
  for (const img of document.images) {
    if (!img.complete || img.naturalWidth === 0) console.error("image failed: " + img.alt);
  }
});
</script>"""

MODE_TEXT = {
    "live": "the frontend was paced at each trace's own timing and never waited; each shown frame "
            "was kept with the pose it was drawn for and scored after the replay against that "
            "pose's full-quality reference.",
    "lockstep": "each frame waited for its plan (and the backbone for the simplifier); "
                "deterministic, not what a thin client sees.",
}


DOC_BEGIN, DOC_END = "<!-- workbench:begin -->", "<!-- workbench:end -->"


def write_doc(doc, out_dir, settings, metrics, table_text, plots):
    """Replaces the generated block of `doc` (see the usage); returns the images copied."""
    with open(doc) as f:
        text = f.read()
    if DOC_BEGIN not in text or DOC_END not in text:
        raise SystemExit(f"workbench_report: {doc} has no {DOC_BEGIN} ... {DOC_END} block")
    img_dir = os.path.join(os.path.dirname(os.path.abspath(doc)), "img")
    os.makedirs(img_dir, exist_ok=True)
    lines = [DOC_BEGIN,
             f"Generated by `{settings.get('command', 'deploy/compare')}` on "
             f"{settings.get('started', '?')}: {settings.get('runs', len(metrics))} runs, mode "
             f"**{settings.get('mode', '?')}**, {settings.get('wall_s', '?')} s wall "
             f"(`deploy/workbench_report.py` wrote this block; do not edit it by hand). "
             "The best median SNR of each case is in bold.", "", table_text]
    copied = []
    for case, png in plots.items():
        if not png:
            continue
        name = f"workbench-snr-{case}.png"
        shutil.copyfile(png, os.path.join(img_dir, name))
        copied.append(name)
        lines += [f"![{case}: SNR per shown frame, every scheduler](img/{name})", ""]
        runs = [m for m in metrics if m["case"] == case]
        frame = pick_frame([os.path.join(out_dir, m["name"]) for m in runs])
        curves = next((m for m in runs if m["scheduler"] == "curves"), None)
        if frame is None or curves is None:
            continue
        pair = []
        for kind in ("frame", "reference"):
            src = os.path.join(out_dir, curves["name"], "frames", f"{kind}_{frame:04d}.png")
            if os.path.exists(src):
                name = f"workbench-{case}-curves-{kind}{frame}.png"
                shutil.copyfile(src, os.path.join(img_dir, name))
                copied.append(name)
                pair.append(f"![{case}, curves, {kind} {frame}](img/{name})")
        if pair:
            lines += [f"{case}, frame {frame}: what `curves` showed (left) and the reference "
                      f"of the same pose (right).", "", " ".join(pair), ""]
    lines.append(DOC_END)
    head, rest = text.split(DOC_BEGIN, 1)
    tail = rest.split(DOC_END, 1)[1]
    with open(doc, "w") as f:
        f.write(head + "\n".join(lines) + tail)
    return copied


def main(argv):
    if "-h" in argv or "--help" in argv:
        print(__doc__)
        return 0
    doc, from_time = None, None
    if "--from-time" in argv:
        i = argv.index("--from-time")
        if i + 1 >= len(argv) or math.isnan(number(argv[i + 1])):
            print(__doc__, file=sys.stderr)
            return 2
        from_time = number(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    if "--doc" in argv:
        i = argv.index("--doc")
        if i + 1 >= len(argv):
            print(__doc__, file=sys.stderr)
            return 2
        doc = argv[i + 1]
        argv = argv[:i] + argv[i + 2:]
    if len(argv) != 1:
        print(__doc__, file=sys.stderr)
        return 2
    out_dir = argv[0]
    settings_path = os.path.join(out_dir, "settings.json")
    settings = json.load(open(settings_path)) if os.path.exists(settings_path) else {}
    names = sorted(d for d in os.listdir(out_dir)
                   if os.path.exists(os.path.join(out_dir, d, "run.json")))
    if not names:
        print(f"workbench_report: no run folder with run.json in {out_dir}", file=sys.stderr)
        return 1
    metrics, metas, rows_by_run = [], [], {}
    for n in names:
        m, meta, rows = run_metrics(os.path.join(out_dir, n), from_time)
        with open(os.path.join(out_dir, n, "metrics.json"), "w") as f:
            json.dump(m, f, indent=2)
        with open(os.path.join(out_dir, n, "metrics.csv"), "w", newline="") as f:
            writer = csv.writer(f)
            writer.writerow(list(m))
            writer.writerow(["" if v is None else v for v in m.values()])
        metrics.append(m)
        metas.append(meta)
        rows_by_run[n] = rows
    # Suite order of cases when known, then scheduler order as run.
    order = settings.get("cases", [])
    schedulers = settings.get("schedulers", [])
    rank = lambda x, xs: xs.index(x) if x in xs else len(xs)
    metrics.sort(key=lambda m: (rank(m["case"], order), m["case"] or "", m["budget_polygons"] or 0,
                                rank(m["scheduler"], schedulers), m["scheduler"] or ""))
    text = write_tables(out_dir, metrics)
    plots = {}
    for case in dict.fromkeys(m["case"] for m in metrics):
        runs = [(m["name"], rows_by_run[m["name"]]) for m in metrics if m["case"] == case]
        plots[case] = plot_case(out_dir, case, runs)
    write_page(out_dir, settings, metrics, metas, rows_by_run, plots)
    if doc:
        copied = write_doc(doc, out_dir, settings, metrics, text, plots)
        print(f"workbench_report: wrote the table into {doc} and {len(copied)} images", file=sys.stderr)
    print(text, end="")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
