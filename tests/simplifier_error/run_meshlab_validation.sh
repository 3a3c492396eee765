#!/bin/sh
# Independent check of measureSurfaceError against MeshLab's "Hausdorff
# Distance" filter (docs/results/error-validation.md). Not a ctest test:
# MeshLab is not a project dependency.
#   apt-get install -y meshlab xvfb xauth
#   run_meshlab_validation.sh <build_dir> <model.obj> <out_dir> <triangles>...
set -eu
build=$1; model=$2; out=$3; shift 3
mkdir -p "$out"
"$build/tests/simplifier_error/error_validation_tool" "$model" "$out" "$@" > "$out/thinlod.jsonl"
cat "$out/thinlod.jsonl"

# script <sampled mesh> <target mesh> <sample vertices and edges: true|false>
# MaxDist is an absolute cut-off (samples farther away are ignored), so it is
# set far above any error.
script() {
  cat <<XML
<!DOCTYPE FilterScript>
<FilterScript>
 <filter name="Hausdorff Distance">
  <Param type="RichMesh" value="$1" name="SampledMesh"/>
  <Param type="RichMesh" value="$2" name="TargetMesh"/>
  <Param type="RichBool" value="false" name="SaveSample"/>
  <Param type="RichBool" value="$3" name="SampleVert"/>
  <Param type="RichBool" value="$3" name="SampleEdge"/>
  <Param type="RichBool" value="false" name="SampleFauxEdge"/>
  <Param type="RichBool" value="true" name="SampleFace"/>
  <Param type="RichInt" value="100000" name="SampleNum"/>
  <Param type="RichAbsPerc" value="1000" min="0" max="1000" name="MaxDist"/>
 </filter>
</FilterScript>
XML
}
# Per direction two runs: with vertex+edge+face samples (for the max, like
# thinlod) and with face samples only (MeshLab's mean averages all samples,
# thinlod's only the area-weighted ones).
script 0 1 true > "$out/forward.mlx"
script 1 0 true > "$out/backward.mlx"
script 0 1 false > "$out/forward_faces.mlx"
script 1 0 false > "$out/backward_faces.mlx"
for n in "$@"; do
  for dir in forward backward forward_faces backward_faces; do
    echo "== $n $dir"
    xvfb-run -a meshlabserver -i "$out/original.ply" -i "$out/simplified_$n.ply" \
      -s "$out/$dir.mlx" -l "$out/meshlab_${n}_$dir.log" > /dev/null 2>&1 || true
    grep -A3 "Hausdorff Distance computed" "$out/meshlab_${n}_$dir.log" || cat "$out/meshlab_${n}_$dir.log"
  done
done
