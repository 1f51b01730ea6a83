#!/usr/bin/env bash
# Clicking the panel's Pause checkbox with a real mouse click (xdotool, inside Xvfb) stops the
# simulation: frames keep coming, simulated time and body centres stay unchanged. Then the
# space key resumes it.
# usage: pause_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
enter_xvfb "$@"

"$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --frames 100000 --stats "$WORK/live.json" --stats-every 5 >"$WORK/viewer.log" 2>&1 &
VIEWER_PID=$!
trap '[ -n "${VIEWER_PID:-}" ] && kill "$VIEWER_PID" 2>/dev/null || true' EXIT
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
"$CHECK" still "$WORK/paused0.json" "$WORK/paused1.json" || fail "the bodies moved after clicking Pause"

# The space key resumes (keyboard shortcut; the key is held briefly like a person would).
xdotool mousemove 900 400
xdotool keydown space
sleep 0.1
xdotool keyup space
now=$("$CHECK" get "$WORK/live.json" /frame)
snapshot "$WORK/live.json" $((now + 20)) "$WORK/resumed.json"
kill "$VIEWER_PID"
wait "$VIEWER_PID" 2>/dev/null || true
VIEWER_PID=
[ "$("$CHECK" get "$WORK/resumed.json" /paused)" = false ] || fail "space did not resume"
t2=$("$CHECK" get "$WORK/paused1.json" /simTime)
t3=$("$CHECK" get "$WORK/resumed.json" /simTime)
[ "$t2" != "$t3" ] || fail "the simulation did not run again after space"

# Started paused, the viewer neither steps nor deforms the render meshes (they were deformed
# once when the scene opened): both per-frame times are exactly zero.
"$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --paused --frames 30 --stats "$WORK/idle.json" \
  >"$WORK/idle.log" 2>&1 || { cat "$WORK/idle.log"; fail "the paused run failed"; }
[ "$("$CHECK" get "$WORK/idle.json" /msPerFrame/simulation)" = 0 ] || fail "a paused viewer stepped"
[ "$("$CHECK" get "$WORK/idle.json" /msPerFrame/deform)" = 0 ] ||
  fail "a paused viewer deformed its meshes again every frame"
echo "PASS: clicking Pause stopped the simulation; space resumed it ($t2 s -> $t3 s); paused, nothing is stepped or deformed"
