#!/usr/bin/env bash
# thinlod-simplifier impostor: a simple and a meshed impostor of the cow come
# back with plausible coverage, a validity cone containing the viewpoint
# direction, encoded sizes and the output files; a missing input and a bad
# option fail with a non-zero exit code and a message.
set -euo pipefail
tool=$1 cow=$2 out=$3
mkdir -p "$out"
"$tool" impostor "$cow" --json --size 128 -o "$out/simple.tltx" >"$out/simple.json"
"$tool" impostor "$cow" --json --size 128 --meshed --mesh-output "$out/depth.ply" >"$out/meshed.json"
python3 - "$out" <<'PY'
import json, os, sys
out = sys.argv[1]
for name in ("simple", "meshed"):
    r = json.load(open(os.path.join(out, name + ".json")))
    assert r["ok"] is True, r
    assert 0.1 < r["coverage"] < 0.95, (name, r["coverage"])
    v = r["validity"]
    assert v["direction"][2] > 0.99, (name, v)          # the default capture direction is +Z
    assert 0.0 < v["half_angle"] < 3.15, (name, v)
    assert r["texture_encoded_bytes"]["zstd"] > 0 and r["texture_encoded_bytes"]["png"] > 0
    print(name, "coverage", round(r["coverage"], 3), "half angle", v["half_angle"])
meshed = json.load(open(os.path.join(out, "meshed.json")))
assert meshed["mesh_triangles"] > 0 and meshed["mesh_encoded_bytes"] > 0
assert os.path.getsize(os.path.join(out, "simple.tltx")) == \
    json.load(open(os.path.join(out, "simple.json")))["texture_encoded_bytes"]["zstd"]
assert os.path.getsize(os.path.join(out, "depth.ply")) > 0
PY
if "$tool" impostor "$out/missing.obj" 2>"$out/missing.err"; then
  echo "FAIL: a missing input succeeded"; exit 1
fi
grep -q "missing.obj" "$out/missing.err" || { echo "FAIL: the error does not name the file"; cat "$out/missing.err"; exit 1; }
if "$tool" impostor "$cow" --direction 0 0 0 2>"$out/direction.err"; then
  echo "FAIL: a zero direction succeeded"; exit 1
fi
grep -q "direction" "$out/direction.err" || { echo "FAIL: no message about --direction"; exit 1; }
echo "impostor command: all checks passed"
