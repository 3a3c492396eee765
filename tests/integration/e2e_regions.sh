#!/usr/bin/env bash
# Runs the three daemons on loopback over a terrain strip (4 x 16 m, 2,048
# triangles) whose Inline has `regions 4` (docs/regions.md, "In the running
# system"), 20 lockstep frames low over its near end looking along it,
# budget 1,200 polygons, impostors off, and checks from frames.csv, the
# simplifier's log and the dumped frames that
# - polygons <= 1200 on every frame and SNR finite above 20 dB;
# - the simplifier served the 4 region objects (ids 1-4) and the levels of
#   the nearest region (4) hold more triangles than the farthest (1), last
#   answer of each;
# - no hole: no background pixel with three or more non-background
#   neighbours where the reference is drawn, in every dumped frame (cracks
#   between regions, or the slivers of per-region quantization grids, show
#   as such pixels: 2-9 a frame before the regions shared one grid).
# Usage: e2e_regions.sh BUILD_DIR OUT_DIR
set -euo pipefail
build=$1 out=$2
root=$(cd "$(dirname "$0")/../.." && pwd)
rm -rf "$out"; mkdir -p "$out/data"
python3 - "$out/data" <<'PY'
import math, sys
d = sys.argv[1]
nx, nz, s = 17, 65, 0.25
def h(x, z): return 0.3 * math.sin(1.3 * x) * math.cos(0.7 * z) + 0.1 * math.sin(3.1 * x + 1.7 * z)
with open(f"{d}/strip.obj", "w") as f:
    for j in range(nz):
        for i in range(nx):
            x, z = -2 + i * s, -16 + j * s
            f.write(f"v {x} {h(x, z)} {z}\n")
    for j in range(nz - 1):
        for i in range(nx - 1):
            a = j * nx + i + 1; b = a + 1; c = a + nx; e = c + 1
            f.write(f"f {a} {c} {e}\nf {a} {e} {b}\n")
with open(f"{d}/strip-regions.wrl", "w") as f:
    f.write('#VRML V2.0 utf8\nDirectionalLight { direction 0.3 -1 -0.5 }\n'
            'Shape { appearance Appearance { material Material { diffuseColor 0.5 0.7 0.4 } }\n'
            '  geometry Inline { url "strip.obj" regions 4 } }\n')
with open(f"{d}/low.trace", "w") as f:
    f.write("# thinlod-trace 1\n# low over the near end of the strip, looking along it\n")
    for k in range(20):
        f.write(f"{0.05 * k:.3f} 0 1.2 {1.0 - 0.02 * k:.3f} lookat 0 0 -12 50\n")
PY
d=$out/data
THINLOD_BUILD_DIR=$build THINLOD_READY_TIMEOUT_S=300 "$root/deploy/run-local" "$out" \
  --backbone "--scene $d/strip-regions.wrl --models-dir $d --max-speed 0.1 --lifetime 1.0 --sync-wait-ms 5000 --budget-polygons 1200 --simple-impostor-radii 0 --meshed-impostor-radii 0" \
  --simplifier "--scene $d/strip-regions.wrl --models-dir $d --scene-root / --cache-dir $out/cache" \
  --frontend "--scene $d/strip-regions.wrl --models-dir $d --trace $d/low.trace --lockstep --lockstep-timeout-ms 20000 --rate -1 --frames 20 --width 320 --height 240 --csv $out/frames.csv --frames-dir $out/dump --dump-every 5"
python3 - "$out" "$root" <<'PY'
import csv, math, os, re, sys

sys.path.insert(0, os.path.join(sys.argv[2], "tests", "workbench"))
from page_test import decode_png  # noqa: E402

out = sys.argv[1]
errors = []
rows = list(csv.DictReader(open(os.path.join(out, "frames.csv"))))
if len(rows) != 20:
    errors.append(f"{len(rows)} rows, expected 20")
for r in rows:
    if float(r["polygons"]) > 1200:
        errors.append(f"frame {r['frame']}: {r['polygons']} polygons > 1200")
    snr = float(r["snr_db"])
    if not (math.isfinite(snr) and snr > 20.0):
        errors.append(f"frame {r['frame']}: SNR {r['snr_db']}")
last = {}
for line in open(os.path.join(out, "simplifier.log")):
    m = re.search(r"event=simplify_done .*object=(\d+) .*triangles=(\d+) ", line)
    if m:
        last[int(m.group(1))] = int(m.group(2))
if sorted(last) != [1, 2, 3, 4]:
    errors.append(f"objects served {sorted(last)}, expected the 4 regions")
elif not last[4] > last[1]:
    errors.append(f"nearest region {last[4]} triangles, farthest {last[1]}")


def read_png(path):
    with open(path, "rb") as f:
        return decode_png(f.read())


holes_per_frame = []
for k in ("0000", "0005", "0010", "0015"):
    w, h, c, frame = read_png(os.path.join(out, "dump", f"frame_{k}.png"))
    _, _, rc, ref = read_png(os.path.join(out, "dump", f"reference_{k}.png"))
    bg = lambda img, cc, x, y: max(img[y][x * cc:x * cc + 3]) < 20
    holes = 0
    for y in range(1, h - 1):
        for x in range(1, w - 1):
            if bg(frame, c, x, y) and not bg(ref, rc, x, y):
                drawn = sum(not bg(frame, c, x + dx, y + dy)
                            for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)))
                holes += drawn >= 3
    holes_per_frame.append(holes)
    if holes:
        errors.append(f"frame {k}: {holes} hole pixels inside the terrain")
print(f"last triangles per region {last}; hole pixels {holes_per_frame}; "
      f"polygons {[r['polygons'] for r in rows]}")
for e in errors:
    print("FAIL:", e)
sys.exit(1 if errors else 0)
PY
