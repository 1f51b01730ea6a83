#!/bin/sh
# The export round trip through a real client: softbody writes a scene's render meshes as a
# rest mesh, an OBJ sequence, PC2 and MDD point caches and a glTF take; Blender (headless)
# imports the rest mesh, plays each cache with its Mesh Cache modifier, imports the glTF with
# its own importer, and compares every frame with the sequence (blender_check.py).
#   roundtrip.sh SOFTBODY BLENDER SCENE OUT_DIR
set -eu
softbody=$1 blender=$2 scene=$3 out=$4
here=$(dirname "$0")
# A step of 1/80 s and a frame every 20 steps: 0.25 s per frame, six of Blender's default
# 24 frames per second, so the glTF keys fall on whole scene frames.
steps=120 every=20 dt=0.0125
rm -rf "$out"
mkdir -p "$out"
"$softbody" run "$scene" --steps $steps --every $every --dt $dt --threads 2 \
  --export-mesh "$out/rest.obj" --export-meshes "$out/seq" \
  --export-pc2 "$out/take.pc2" --export-mdd "$out/take.mdd" --export-gltf "$out/take.glb" \
  >"$out/run.log"
frame_seconds=0.25
status=0
"$blender" -b --factory-startup --python-exit-code 1 --python "$here/blender_check.py" -- \
  "$out/rest.obj" "$out/seq" $every $((steps / every + 1)) "$out/take.pc2" "$out/take.mdd" \
  "$out/take.glb" "$frame_seconds" >"$out/blender.log" 2>&1 || status=$?
grep "blender_check" "$out/blender.log" || true
if [ $status -ne 0 ]; then
  echo "roundtrip: Blender exited with $status; its output is in $out/blender.log:" >&2
  tail -n 20 "$out/blender.log" >&2
fi
exit $status
