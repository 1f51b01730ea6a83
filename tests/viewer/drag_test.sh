#!/usr/bin/env bash
# A real mouse drag (xdotool, inside Xvfb) on body 0 moves it along the drag direction, compared
# with the same run without the drag.
# usage: drag_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
if [ "${INNER:-0}" != 1 ]; then
  mkdir -p "$WORK"
  rm -f "$WORK"/*.json
  INNER=1 exec xvfb-run -a -s "$XVFB_SERVER_ARGS" bash "$0" "$@" </dev/null
fi

FRAMES=300
start_viewer() {  # start_viewer STATS
  "$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --frames $FRAMES --stats "$1" --stats-every 5 >"$WORK/viewer.log" 2>&1 &
  VIEWER_PID=$!
}

# Reference: no input at all.
start_viewer "$WORK/ref.json"
finish_viewer

# The same with a drag: grab body 0 after the scene settled, pull it 240 px to the right.
start_viewer "$WORK/drag.json"
wait_for_frame "$WORK/drag.json" 90
read -r x y < <("$CHECK" grab-pixel "$WORK/drag.json" 0)
echo "grabbing body 0 at pixel $x,$y"
xdotool mousemove "$x" "$y"
sleep 0.2
xdotool mousedown 1
for step in $(seq 1 12); do
  xdotool mousemove $((x + 20 * step)) "$y"
  sleep 0.05
done
now=$("$CHECK" get "$WORK/drag.json" /frame)
wait_for_frame "$WORK/drag.json" $((now + 60))
active=$("$CHECK" get "$WORK/drag.json" /drag/active)
xdotool mouseup 1
finish_viewer
[ "$active" = true ] || fail "the viewer did not report an active drag while the button was held"
"$CHECK" moved "$WORK/ref.json" "$WORK/drag.json" 0 0.15 || fail "the dragged body did not follow the mouse"
echo "PASS: dragging moved body 0"
