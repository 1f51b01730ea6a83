#!/usr/bin/env bash
# The viewer steps the simulation on a second thread while it draws the frame. This runs it on
# the pile with every overlay on and the stats file written every frame (both read the World
# around the step), a drag included: it must finish with exit code 0 after all its frames. The
# TSan stage of CI runs it too (it runs no other viewer test), so a data race between the step
# and the drawing fails there.
# usage: step_thread_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
enter_xvfb "$@"

"$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --frames 150 --show particles,cage,clusters,goals \
  --stats "$WORK/live.json" --stats-every 1 >"$WORK/viewer.log" 2>&1 &
VIEWER_PID=$!
trap '[ -n "${VIEWER_PID:-}" ] && kill "$VIEWER_PID" 2>/dev/null || true' EXIT
wait_for_frame "$WORK/live.json" 20 300
read -r x y < <("$CHECK" grab-pixel "$WORK/live.json" 0) || fail "no pixel hits body 0"
xdotool mousemove "$x" "$y"
sleep 0.2
xdotool mousedown 1
for step in $(seq 1 8); do
  xdotool mousemove $((x + 15 * step)) "$y"
  sleep 0.05
done
xdotool mouseup 1
finish_viewer
cat "$WORK/viewer.log"
[ "$("$CHECK" get "$WORK/live.json" /frame)" = 150 ] || fail "the viewer did not draw all 150 frames"
! grep -q "ThreadSanitizer" "$WORK/viewer.log" || fail "ThreadSanitizer reported a race"
echo "PASS: 150 frames with the step on its own thread, overlays, stats and a drag"
