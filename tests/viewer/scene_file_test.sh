#!/usr/bin/env bash
# The Scene file controls, operated with real mouse clicks and typing (xdotool, inside Xvfb):
# opening a bad scene file shows its error in the window and the current scene keeps running;
# saving writes a scene file that loads again.
# usage: scene_file_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
enter_xvfb "$@"

# A scene with an out-of-range field.
printf '{ "bodies": [ { "name": "b", "mesh": "x.obj", "alpha": 3 } ] }\n' >"$WORK/bad_scene.json"
live=$WORK/live.json

start_live_viewer "$live"
scene=$("$CHECK" get "$live" /scenePath)

click_widget "$live" sceneHeader
next_frames "$live" 5
click_widget "$live" scenePath
replace_text "$WORK/bad_scene.json"
click_widget "$live" open
next_frames "$live" 5
copy_stats "$live" "$WORK/after_open.json"
error=$("$CHECK" get "$WORK/after_open.json" /error)
echo "error shown: $error"
case "$error" in
  *bad_scene.json*alpha*) ;;
  *) fail "the window does not show the bad scene's error" ;;
esac
[ "$("$CHECK" get "$WORK/after_open.json" /scenePath)" = "$scene" ] || fail "the scene was replaced"
t0=$("$CHECK" get "$WORK/after_open.json" /simTime)
next_frames "$live" 10
t1=$("$CHECK" get "$live" /simTime)
[ "$t0" != "$t1" ] || fail "the current scene stopped running"

click_widget "$live" savePath
replace_text "$WORK/saved_scene.json"
click_widget "$live" save
next_frames "$live" 5
status=$("$CHECK" get "$live" /status)
echo "status: $status"
[ -s "$WORK/saved_scene.json" ] || fail "no scene file saved"
kill "$VIEWER_PID" 2>/dev/null || true
wait "$VIEWER_PID" 2>/dev/null || true
VIEWER_PID=
env -u DISPLAY "$SOFTBODY" "$WORK/saved_scene.json" --frames 5 >"$WORK/reload.log" 2>&1 ||
  { cat "$WORK/reload.log"; fail "the saved scene does not load"; }
echo "PASS: bad scene error shown while the scene kept running; saved scene loads"
