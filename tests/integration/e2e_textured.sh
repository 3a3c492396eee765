#!/usr/bin/env bash
# Runs the three daemons on loopback with a textured scene from assimp-testmodels
# (imported as the scene file itself: glTF 2.0 or Collada) and checks that the
# frontend's own frames show the texture, as its full-quality reference does:
# - 20 frames, something drawn, SNR finite on every drawn frame;
# - on every dumped frame (every 5th): >= 20% of the object's pixels (non-black
#   in the reference) are saturated (HSV saturation (max - min) / max > 0.3) in
#   the frame AND in the reference. Both scenes' materials are white (the
#   texture gives all the colour) and the light is white, so an untextured
#   drawing is grey: 0% saturated, whatever the shading. The 20% floor is
#   well below the least saturated share these scenes show (box 0.56, duck
#   0.96 in the frames; docs/frontend.md, "Textured scenes").
# - the frame's mean object colour is within 40/255 per channel of the
#   reference's: the same texture, not just any colour.
# Usage: e2e_textured.sh BUILD_DIR OUT_DIR SCENE TRACE BUDGET
set -euo pipefail
build=$1 out=$2 scene=$3 trace=$4 budget=$5
root=$(cd "$(dirname "$0")/../.." && pwd)
if [ ! -f "$scene" ]; then
  echo "FAIL: $scene is missing: install assimp-testmodels (deploy/setup does)"; exit 1
fi
rm -rf "$out"; mkdir -p "$out"
THINLOD_BUILD_DIR=$build THINLOD_READY_TIMEOUT_S=300 "$root/deploy/run-local" "$out" \
  --backbone "--scene $scene --max-speed 1.0 --lifetime 1.0 --sync-wait-ms 5000 --budget-polygons $budget" \
  --simplifier "--scene $scene --scene-root / --cache-dir $out/cache" \
  --frontend "--scene $scene --trace $trace --lockstep --lockstep-timeout-ms 20000 --rate -1 --frames 20 --width 320 --height 240 --csv $out/frames.csv --frames-dir $out/dump --dump-every 5"
python3 - "$out" "$root" <<'PY'
import csv, glob, math, os, sys

sys.path.insert(0, os.path.join(sys.argv[2], "tests", "workbench"))
from page_test import decode_png  # noqa: E402  (the project's one PNG reader for tests)


def read_png(path):
    with open(path, "rb") as f:
        return decode_png(f.read())


out = sys.argv[1]
errors = []
rows = list(csv.DictReader(open(os.path.join(out, "frames.csv"))))
if len(rows) != 20:
    errors.append(f"{len(rows)} rows, expected 20")
drawn = [r for r in rows if float(r["polygons"]) > 0]
if not drawn:
    errors.append("the frontend never drew anything")
for r in drawn:
    if not math.isfinite(float(r["snr_db"])):
        errors.append(f"frame {r['frame']}: SNR {r['snr_db']} not finite")
SATURATED, FLOOR, MEAN_TOLERANCE = 0.3, 0.20, 40
saturated = lambda p: max(p) > 0 and (max(p) - min(p)) / max(p) > SATURATED
frames = sorted(glob.glob(os.path.join(out, "dump", "frame_*.png")))
if len(frames) != 4:
    errors.append(f"{len(frames)} dumped frames, expected 4")
for frame_path in frames:
    ref_path = frame_path.replace("frame_", "reference_")
    fw, fh, fc, frame = read_png(frame_path)
    rw, rh, rc, ref = read_png(ref_path)
    assert (fw, fh) == (rw, rh)
    covered = sat_frame = sat_ref = 0
    mean_f, mean_r = [0, 0, 0], [0, 0, 0]
    for y in range(fh):
        for x in range(fw):
            r = ref[y][x * rc:x * rc + 3]
            if sum(r) <= 30:
                continue
            f = frame[y][x * fc:x * fc + 3]
            covered += 1
            sat_ref += saturated(r)
            sat_frame += saturated(f)
            for k in range(3):
                mean_f[k] += f[k]; mean_r[k] += r[k]
    name = os.path.basename(frame_path)
    if covered < 500:
        errors.append(f"{name}: the object covers {covered} reference pixels"); continue
    mean_f = [v / covered for v in mean_f]; mean_r = [v / covered for v in mean_r]
    share_f, share_r = sat_frame / covered, sat_ref / covered
    print(f"{name}: {covered} object pixels, saturated frame {share_f:.2f} reference {share_r:.2f}, "
          f"mean rgb frame {[round(v) for v in mean_f]} reference {[round(v) for v in mean_r]}")
    if share_r < FLOOR:
        errors.append(f"{name}: reference only {share_r:.2f} saturated (< {FLOOR})")
    if share_f < FLOOR:
        errors.append(f"{name}: frame only {share_f:.2f} saturated (< {FLOOR}): untextured?")
    if max(abs(a - b) for a, b in zip(mean_f, mean_r)) > MEAN_TOLERANCE:
        errors.append(f"{name}: mean colour {mean_f} differs from the reference's {mean_r}")
median = sorted(float(r["snr_db"]) for r in drawn)[len(drawn) // 2] if drawn else float("nan")
for e in errors:
    print("FAIL:", e)
print(f"{len(rows)} frames, median SNR {median:.2f} dB, {len(errors)} problems")
sys.exit(1 if errors else 0)
PY
