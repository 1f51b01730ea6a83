#!/usr/bin/env bash
# A real mouse drag (xdotool, inside Xvfb) on body 0 moves it along the drag direction, compared
# with the same run without the drag: once grabbing the surface point, once (Ctrl held) the
# nearest particle.
# usage: drag_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
enter_xvfb "$@"

FRAMES=300
start_viewer() {  # start_viewer STATS
  "$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --frames $FRAMES --stats "$1" --stats-every 5 >"$WORK/viewer.log" 2>&1 &
  VIEWER_PID=$!
}

# Reference: no input at all.
start_viewer "$WORK/ref.json"
finish_viewer

# drag_run STATS [MODIFIER]: grab body 0 after the scene settled (with MODIFIER held, if given),
# pull it 240 px to the right, hold, release. Leaves the stats seen while holding in STATS.held.
drag_run() {
  local stats=$1 modifier=${2:-} x y now
  start_viewer "$stats"
  wait_for_frame "$stats" 90
  read -r x y < <("$CHECK" grab-pixel "$stats" 0)
  echo "grabbing body 0 at pixel $x,$y ${modifier:+with $modifier held}"
  xdotool mousemove "$x" "$y"
  sleep 0.2
  [ -n "$modifier" ] && xdotool keydown "$modifier"
  xdotool mousedown 1
  for step in $(seq 1 12); do
    xdotool mousemove $((x + 20 * step)) "$y"
    sleep 0.05
  done
  now=$("$CHECK" get "$stats" /frame)
  snapshot "$stats" $((now + 60)) "$stats.held"
  xdotool mouseup 1
  [ -n "$modifier" ] && xdotool keyup "$modifier"
  finish_viewer
  [ "$("$CHECK" get "$stats.held" /drag/active)" = true ] ||
    fail "the viewer did not report an active drag while the button was held"
  [ "$("$CHECK" get "$stats.held" /drag/body)" = 0 ] || fail "the drag grabbed another body"
}

# A surface point: its weights spread over many particles.
drag_run "$WORK/drag.json"
[ "$("$CHECK" get "$WORK/drag.json.held" /drag/nearestParticle)" = false ] || fail "not a surface drag"
"$CHECK" moved "$WORK/ref.json" "$WORK/drag.json" 0 0.15 || fail "the dragged body did not follow the mouse"

# Ctrl + drag: the nearest particle alone.
drag_run "$WORK/ctrl.json" ctrl
[ "$("$CHECK" get "$WORK/ctrl.json.held" /drag/nearestParticle)" = true ] || fail "Ctrl did not pick a particle"
[ "$("$CHECK" get "$WORK/ctrl.json.held" /drag/particles)" = 1 ] || fail "Ctrl drag holds more than one particle"
"$CHECK" moved "$WORK/ref.json" "$WORK/ctrl.json" 0 0.15 || fail "the Ctrl-dragged body did not follow the mouse"
echo "PASS: dragging a surface point and (with Ctrl) a particle moved body 0"
