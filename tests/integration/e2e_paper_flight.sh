#!/usr/bin/env bash
# Runs the three daemons on loopback over the first 20 frames of the paper
# flight path and checks the frontend's per-frame CSV:
# - 20 rows with the documented columns;
# - with a polygon budget, polygons <= budget on every frame;
# - SNR finite and above a floor on every frame whose reference is not blank
#   (a blank reference has SNR -inf/nan by definition, docs/frontend.md);
# - the frontend received something (polygons > 0 on some frame).
# Usage: e2e_paper_flight.sh BUILD_DIR MODELS_DIR OUT_DIR "BACKBONE ARGS"
set -euo pipefail
build=$1 models=$2 out=$3 args=$4
root=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$out"; mkdir -p "$out"
THINLOD_BUILD_DIR=$build THINLOD_READY_TIMEOUT_S=300 "$root/deploy/run-local" "$out" \
  --backbone "--scene $root/deploy/data/paper-room.wrl --models-dir $models --max-speed 0.1 --lifetime 1.0 --sync-wait-ms 5000 $args --decisions-csv $out/decisions.csv" \
  --simplifier "--scene $root/deploy/data/paper-room.wrl --models-dir $models --scene-root / --cache-dir $build/cache" \
  --frontend "--scene $root/deploy/data/paper-room.wrl --models-dir $models --trace $root/deploy/data/paper-flight.trace --lockstep --lockstep-timeout-ms 20000 --rate -1 --frames 20 --width 320 --height 240 --csv $out/frames.csv"
python3 - "$out/frames.csv" "$args" <<'PY'
import csv, math, shlex, sys
path, args = sys.argv[1], shlex.split(sys.argv[2])
budget = float(args[args.index("--budget-polygons") + 1]) if "--budget-polygons" in args else None
rows = list(csv.DictReader(open(path)))
required = ["frame", "time_s", "polygons", "link_bytes", "target_accuracy", "snr_db", "psnr_db",
            "render_ms", "pose_to_frame_ms"]
errors = []
missing = [c for c in required if c not in (rows[0].keys() if rows else [])]
if missing:
    errors.append(f"missing columns {missing}")
if len(rows) != 20:
    errors.append(f"{len(rows)} rows, expected 20")
SNR_FLOOR_DB = 0.0  # a frame showing the scene at all beats a blank frame's 0 dB
for r in rows:
    polygons = float(r["polygons"])
    if budget is not None and polygons > budget:
        errors.append(f"frame {r['frame']}: {polygons} polygons > budget {budget}")
    snr = float(r["snr_db"])
    if polygons > 0 and not (math.isfinite(snr) and snr > SNR_FLOOR_DB):
        errors.append(f"frame {r['frame']}: SNR {r['snr_db']} not finite above {SNR_FLOOR_DB} dB")
if not any(float(r["polygons"]) > 0 for r in rows):
    errors.append("the frontend never drew anything")
for e in errors:
    print("FAIL:", e)
print(f"{len(rows)} frames checked, {len(errors)} problems")
sys.exit(1 if errors else 0)
PY
