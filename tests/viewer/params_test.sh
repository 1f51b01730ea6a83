#!/usr/bin/env bash
# Undo and reset of body parameters (xdotool, inside Xvfb): values typed into alpha and beta and
# a drag of the alpha slider are undone by Ctrl+Z one edit at a time, newest first; Ctrl+Z with
# nothing left changes nothing; "reset parameters" sets body 0 back to the scene file's and is
# itself undone by Ctrl+Z; with the file's parameters back, Q quits at once (nothing unsaved).
# usage: params_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
enter_xvfb "$@"

live=$WORK/live.json
cd "$WORK"
start_live_viewer "$live"

param() { "$CHECK" get "$live" "/bodies/0/params/$1"; }
# ctrl_z: Ctrl+Z over the 3D view, keys held for a frame (ImGui polls key state once per frame).
ctrl_z() {
  xdotool mousemove 900 200
  sleep 0.15
  xdotool keydown ctrl
  sleep 0.1
  xdotool keydown z
  sleep 0.15
  xdotool keyup z
  sleep 0.1
  xdotool keyup ctrl
  next_frames "$live" 5
}
expect() {  # expect NAME VALUE WHAT
  [ "$(param "$1")" = "$2" ] || fail "$3: $1 is $(param "$1"), expected $2"
}

alpha0=$(param alpha) beta0=$(param beta)
echo "file's alpha $alpha0, beta $beta0"
[ "$alpha0" != 0.05 ] && [ "$beta0" != 0.9 ] || fail "pick other test values for this scene"

ctrl_click_type "$live" alpha 0.05
next_frames "$live" 5
ctrl_click_type "$live" beta 0.9
next_frames "$live" 5
expect alpha 0.05 "typed"
expect beta 0.9 "typed"

# A drag on the alpha slider: from its left end to the right, one undo step however many frames.
read -r x0 y0 x1 y1 < <("$CHECK" get "$live" /widgets/alpha)
xdotool mousemove "${x0%.*}" "$(((${y0%.*} + ${y1%.*}) / 2))"
sleep 0.15
xdotool mousedown 1
sleep 0.15
for f in 1 2 3 4 5; do
  xdotool mousemove_relative 20 0
  sleep 0.1
done
xdotool mouseup 1
next_frames "$live" 5
dragged=$(param alpha)
echo "alpha after the drag: $dragged"
[ "$dragged" != 0.05 ] || fail "the drag did not change alpha"

ctrl_z
expect alpha 0.05 "first Ctrl+Z (the drag)"
ctrl_z
expect beta "$beta0" "second Ctrl+Z (beta typed)"
expect alpha 0.05 "second Ctrl+Z"
ctrl_z
expect alpha "$alpha0" "third Ctrl+Z (alpha typed)"
ctrl_z
expect alpha "$alpha0" "Ctrl+Z with nothing to undo"
expect beta "$beta0" "Ctrl+Z with nothing to undo"
[ "$("$CHECK" get "$live" /status)" = "nothing to undo" ] || fail "no 'nothing to undo' status"

# Reset to the file's, and undo of the reset.
ctrl_click_type "$live" alpha 0.2
next_frames "$live" 5
ctrl_click_type "$live" beta 0.1
next_frames "$live" 5
click_widget "$live" resetParams
next_frames "$live" 5
expect alpha "$alpha0" "reset"
expect beta "$beta0" "reset"
ctrl_z
expect alpha 0.2 "Ctrl+Z after the reset"
expect beta 0.1 "Ctrl+Z after the reset"
click_widget "$live" resetParams
next_frames "$live" 5

# Nothing differs from the file now: Q quits without asking.
xdotool mousemove 900 200
sleep 0.15
xdotool key q
finish_viewer
echo "PASS: Ctrl+Z undoes typed values and a slider drag one edit at a time; reset parameters restores the file's and is undoable; Q quits at once with the file's parameters back"
