#!/bin/sh
# The installed package as a consumer uses it: install this build into a fresh prefix, configure
# and build examples/cpp against that prefix only, step a scene and compare the state hash with
# the softbody program's.
#   consumer.sh CMAKE BUILD_DIR SOURCE_DIR WORK_DIR SCENE
set -eu
cmake=$1 build=$2 source=$3 work=$4 scene=$5
rm -rf "$work"
mkdir -p "$work"
"$cmake" --install "$build" --prefix "$work/prefix" >"$work/install.log"
test -x "$work/prefix/bin/softbody"
"$cmake" -S "$source/examples/cpp" -B "$work/build" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$work/prefix" >"$work/configure.log"
"$cmake" --build "$work/build" -j2 >"$work/build.log"
ours=$("$work/build/step_scene" "$scene" 60 | sed -n 's/^state hash //p')
theirs=$("$work/prefix/bin/softbody" run "$scene" --steps 60 --no-deform | sed -n 's/^state hash \([0-9a-f]*\) .*/\1/p')
echo "installed library: $ours, installed program: $theirs"
[ -n "$ours" ] && [ "$ours" = "$theirs" ]
