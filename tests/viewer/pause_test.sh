#!/usr/bin/env bash
# Clicking the panel's Pause checkbox with a real mouse click (xdotool, inside Xvfb) stops the
# simulation: frames keep coming, simulated time and body centres stay unchanged.
# usage: pause_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
if [ "${INNER:-0}" != 1 ]; then
  mkdir -p "$WORK"
  rm -f "$WORK"/*.json
  INNER=1 exec xvfb-run -a -s "$XVFB_SERVER_ARGS" bash "$0" "$@" </dev/null
fi

"$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --frames 200 --stats "$WORK/live.json" --stats-every 5 >"$WORK/viewer.log" 2>&1 &
VIEWER_PID=$!
snapshot "$WORK/live.json" 10 "$WORK/running0.json"
snapshot "$WORK/live.json" 30 "$WORK/running1.json"
t0=$("$CHECK" get "$WORK/running0.json" /simTime)
t1=$("$CHECK" get "$WORK/running1.json" /simTime)
[ "$t0" != "$t1" ] || fail "the simulation does not run before the click"
[ "$("$CHECK" get "$WORK/running1.json" /paused)" = false ] || fail "paused before the click"

read -r x y < <("$CHECK" click-point "$WORK/running1.json" pause)
echo "clicking Pause at pixel $x,$y"
xdotool mousemove "$x" "$y"
sleep 0.2
xdotool click 1
now=$("$CHECK" get "$WORK/live.json" /frame)
snapshot "$WORK/live.json" $((now + 15)) "$WORK/paused0.json"
now=$("$CHECK" get "$WORK/paused0.json" /frame)
snapshot "$WORK/live.json" $((now + 40)) "$WORK/paused1.json"
finish_viewer
"$CHECK" still "$WORK/paused0.json" "$WORK/paused1.json" || fail "the bodies moved after clicking Pause"
echo "PASS: clicking Pause stopped the simulation"
