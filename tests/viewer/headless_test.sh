#!/usr/bin/env bash
# With no DISPLAY the viewer runs the scene headless, says so, and exits 0.
# usage: headless_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
export ASAN_OPTIONS=${ASAN_OPTIONS%detect_leaks=0}  # no GL driver here: keep leak checking
mkdir -p "$WORK"
code=0
env -u DISPLAY -u WAYLAND_DISPLAY "$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --frames 120 --stats "$WORK/headless.json" \
  >"$WORK/out.txt" 2>&1 </dev/null || code=$?
cat "$WORK/out.txt"
[ "$code" -eq 0 ] || fail "exit code $code"
grep -q "no display: running headless" "$WORK/out.txt" || fail "no 'no display' message"
steps=$("$CHECK" get "$WORK/headless.json" /steps)
[ "$steps" -eq 120 ] || fail "ran $steps steps, expected 120"
echo "PASS: headless fallback ran $steps steps"
