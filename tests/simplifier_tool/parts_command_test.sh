#!/usr/bin/env bash
# thinlod-simplifier parts: the generated multi-manifold model written as a
# PLY has the announced parts x triangles (5 parts at level 1: 5 x 80 faces,
# 5 x 42 vertices) and is the same for the same seed; an unknown extension
# fails with a non-zero exit code and a message.
set -euo pipefail
tool=$1 out=$2
mkdir -p "$out"
"$tool" parts --parts 5 --level 1 --seed 3 -o "$out/parts.ply"
"$tool" parts --parts 5 --level 1 --seed 3 -o "$out/again.ply"
head -c 400 "$out/parts.ply" | grep -a -q "element face 400" || { echo "FAIL: not 400 faces"; exit 1; }
head -c 400 "$out/parts.ply" | grep -a -q "element vertex 210" || { echo "FAIL: not 210 vertices"; exit 1; }
cmp -s "$out/parts.ply" "$out/again.ply" || { echo "FAIL: same seed, different files"; exit 1; }
if "$tool" parts -o "$out/parts.xyz" 2>"$out/ext.err"; then
  echo "FAIL: an unknown extension succeeded"; exit 1
fi
grep -q "parts.xyz" "$out/ext.err" || { echo "FAIL: the error does not name the file"; exit 1; }
echo "parts command: all checks passed"
