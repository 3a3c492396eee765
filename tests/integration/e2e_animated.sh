#!/usr/bin/env bash
# Runs the three daemons on loopback over a scene with an animated, skinned
# figure (Testwuson.X from assimp-testmodels, docs/animation.md "Served") and a
# still camera, 20 lockstep frames 50 ms apart, and checks from the frontend's
# frames.csv and dumped frames that
# - the figure is drawn skinned (skinned_objects 1) in the last 10 frames, with
#   0 < deformed_vertices <= 3205 (the input's vertices; a level's are fewer);
# - bone poses arrive every frame once it is held: link_bytes >= 37 x 48 (its
#   palette's matrices) on each of those frames;
# - it moves: dumped frames 10 and 15 (the camera does not move) differ in
#   more than 1% of their pixels;
# - the reference moves with it (the full mesh skinned at the pose's time):
#   every frame's SNR >= 14 dB (measured 18.4-20.0; a bind-pose reference
#   gave 8.3-10.4, docs/animation.md).
# Usage: e2e_animated.sh BUILD_DIR OUT_DIR
set -euo pipefail
build=$1 out=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
models=/usr/share/assimp/models/X
if [ ! -f "$models/Testwuson.X" ]; then
  echo "FAIL: $models/Testwuson.X is missing: install assimp-testmodels (deploy/setup does)"; exit 1
fi
scene=$root/tests/data/anim/wuson-running.wrl
trace=$root/tests/data/anim/wuson-still.trace
rm -rf "$out"; mkdir -p "$out"
THINLOD_BUILD_DIR=$build THINLOD_READY_TIMEOUT_S=300 "$root/deploy/run-local" "$out" \
  --backbone "--scene $scene --models-dir $models --max-speed 0.1 --lifetime 1.0 --sync-wait-ms 5000 --budget-polygons 2000" \
  --simplifier "--scene $scene --models-dir $models --scene-root / --cache-dir $out/cache" \
  --frontend "--scene $scene --models-dir $models --trace $trace --lockstep --lockstep-timeout-ms 20000 --rate -1 --frames 20 --width 320 --height 240 --csv $out/frames.csv --frames-dir $out/dump --dump-every 5"
python3 - "$out" "$root" <<'PY'
import csv, os, sys

sys.path.insert(0, os.path.join(sys.argv[2], "tests", "workbench"))
from page_test import decode_png  # noqa: E402  (the project's one PNG reader for tests)

out = sys.argv[1]
errors = []
rows = list(csv.DictReader(open(os.path.join(out, "frames.csv"))))
if len(rows) != 20:
    errors.append(f"{len(rows)} rows, expected 20")
POSE_BYTES = 37 * 48
for r in rows[10:]:
    if int(r["skinned_objects"]) != 1:
        errors.append(f"frame {r['frame']}: {r['skinned_objects']} skinned objects drawn, expected 1")
    if not 0 < int(r["deformed_vertices"]) <= 3205:
        errors.append(f"frame {r['frame']}: {r['deformed_vertices']} deformed vertices")
    if int(r["link_bytes"]) < POSE_BYTES:
        errors.append(f"frame {r['frame']}: {r['link_bytes']} link bytes, a pose is {POSE_BYTES}")
for r in rows:
    if not float(r["snr_db"]) >= 14.0:
        errors.append(f"frame {r['frame']}: SNR {r['snr_db']} dB against the animated reference")


def read_png(path):
    with open(path, "rb") as f:
        return decode_png(f.read())


a = read_png(os.path.join(out, "dump", "frame_0010.png"))
b = read_png(os.path.join(out, "dump", "frame_0015.png"))
w, h, c = a[0], a[1], a[2]
differ = sum(1 for y in range(h) for x in range(w)
             if max(abs(a[3][y][x * c + k] - b[3][y][x * c + k]) for k in range(3)) > 16)
print(f"frames 10 and 15 differ in {differ} of {w * h} pixels; "
      f"deformed vertices {[r['deformed_vertices'] for r in rows]}; "
      f"link bytes {[r['link_bytes'] for r in rows]}; SNR {[r['snr_db'] for r in rows]}")
if differ <= w * h // 100:
    errors.append(f"frames 10 and 15 differ in {differ} pixels: the figure does not move")
for e in errors:
    print("FAIL:", e)
sys.exit(1 if errors else 0)
PY
