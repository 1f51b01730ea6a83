#!/usr/bin/env bash
# The panel stays put (xdotool, inside Xvfb): the sliders alpha, beta, c_yield and c_creep of the
# first body are at the same pixels before and after a reset (R) and after an error message
# (messages go to the status bar along the bottom of the 3D view); Ctrl+click on alpha after the
# reset edits alpha; typing into a text field fires no shortcut; Save does not rewrite a shipped
# scene and writes numbers as typed; H hides the panel; Q/Esc with unsaved changes ask first.
# usage: panel_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
enter_xvfb "$@"

printf '{ "bodies": [ { "name": "b", "mesh": "x.obj", "alpha": 3 } ] }\n' >"$WORK/bad_scene.json"
live=$WORK/live.json
cd "$WORK"  # the viewer's current folder: where Save proposes to put an edited shipped scene
start_live_viewer "$live"

# positions STATS: the four sliders' rectangles, one line.
positions() {
  local name
  for name in alpha beta c_yield c_creep; do
    printf '%s=%s ' "$name" "$("$CHECK" get "$1" "/widgets/$name")"
  done
}
# in_view: moves the mouse over the 3D view (keys typed there go to the viewer).
in_view() {
  xdotool mousemove 900 200
  sleep 0.15
}

click_widget "$live" sceneHeader  # opened by hand first: the layout compared is this one
next_frames "$live" 5
before=$(positions "$live")
echo "before:      $before"

in_view
xdotool key r
next_frames "$live" 5
[ "$("$CHECK" get "$live" /status)" = reset ] || fail "R did not reset (status: $("$CHECK" get "$live" /status))"
after_reset=$(positions "$live")
echo "after R:     $after_reset"
[ "$after_reset" = "$before" ] || fail "the sliders moved after R"

click_widget "$live" scenePath
replace_text "$WORK/bad_scene.json"
click_widget "$live" open
next_frames "$live" 5
[ -n "$("$CHECK" get "$live" /error)" ] || fail "no error shown for the bad scene"
after_error=$(positions "$live")
echo "after error: $after_error"
[ "$after_error" = "$before" ] || fail "the sliders moved when the error was shown"

# Typing in a text field fires no shortcut: s (step, pauses), p, r (reset) typed into the path.
t0=$("$CHECK" get "$live" /simTime)
click_widget "$live" scenePath
xdotool type --delay 30 "spr"
sleep 0.2
next_frames "$live" 10
[ "$("$CHECK" get "$live" /paused)" = false ] || fail "typing s into a text field paused"
t1=$("$CHECK" get "$live" /simTime)
awk -v a="$t0" -v b="$t1" 'BEGIN { exit !(b > a) }' || fail "typing r into a text field reset ($t0 -> $t1 s)"

# Ctrl+click on alpha turns the slider into a text field: type a value.
ctrl_click_type "$live" alpha 0.05
next_frames "$live" 5
alpha=$("$CHECK" get "$live" /bodies/0/params/alpha)
echo "alpha after Ctrl+click and typing 0.05: $alpha"
[ "$alpha" = 0.05 ] || fail "Ctrl+click on alpha did not set alpha to 0.05"

# Save: a shipped scene is saved as NAME-edited.json in the current folder, with the numbers as
# typed (0.05, not the float's 0.05000000074505806); the shipped file is not touched, and naming
# it as the target is refused with a message.
scene=$("$CHECK" get "$live" /scenePath)
shipped=false
case "$scene" in */assets/scenes/*.json) shipped=true ;; esac
save_path=$("$CHECK" get "$live" /savePath)
echo "scene $scene (shipped: $shipped), Save proposes $save_path"
if [ "$shipped" = true ]; then
  [ "$save_path" = "$WORK/$(basename "$scene" .json)-edited.json" ] ||
    fail "Save proposes $save_path for a shipped scene"
  sum_before=$(sha256sum <"$scene")
  rm -f "$save_path"
  click_widget "$live" save
  next_frames "$live" 5
  [ -s "$save_path" ] || fail "Save did not write $save_path"
  grep -q '"alpha": 0.05,' "$save_path" || fail "the saved alpha is not written as 0.05"
  # A float widened to double: a long run of 0s or 9s with more digits after it.
  noise='[0-9]\.[0-9]*(0{6}|9{6})[0-9]+'
  if grep -Eq "$noise" "$save_path"; then
    grep -En "$noise" "$save_path" | head -3
    fail "the saved scene has float noise in its numbers"
  fi
  click_widget "$live" savePath
  replace_text "$scene"
  click_widget "$live" save
  next_frames "$live" 5
  case "$("$CHECK" get "$live" /error)" in
    *"shipped scene"*) ;;
    *) fail "saving over the shipped scene gave no error" ;;
  esac
  [ "$(sha256sum <"$scene")" = "$sum_before" ] || fail "the shipped scene was rewritten"
fi

# H hides the panel and shows it again.
in_view
next_frames "$live" 3
[ "$("$CHECK" get "$live" /keyboardToPanel)" = false ] || fail "the panel still takes the keyboard"
xdotool key h
next_frames "$live" 5
[ "$("$CHECK" get "$live" /panelVisible)" = false ] || fail "H did not hide the panel"
xdotool key h
next_frames "$live" 5
[ "$("$CHECK" get "$live" /panelVisible)" = true ] || fail "H did not show the panel again"
[ "$(positions "$live")" = "$before" ] || fail "the sliders moved after hiding and showing the panel"
# Quitting with unsaved changes asks: set alpha again, then Q opens the dialog and the viewer
# keeps running; Cancel closes it; Esc opens it again; "Quit without saving" ends the program
# (exit 0) and leaves the saved file as it was.
[ "$("$CHECK" get "$live" /quitDialog)" = false ] || fail "the quit dialog is open already"
ctrl_click_type "$live" alpha 0.3
next_frames "$live" 5
in_view
xdotool key q
next_frames "$live" 5
[ "$("$CHECK" get "$live" /quitDialog)" = true ] || fail "Q with unsaved changes did not ask"
kill -0 "$VIEWER_PID" 2>/dev/null || fail "the viewer quit with unsaved changes"
click_widget "$live" quitCancel
next_frames "$live" 5
[ "$("$CHECK" get "$live" /quitDialog)" = false ] || fail "Cancel did not close the dialog"
in_view
xdotool key Escape
next_frames "$live" 5
[ "$("$CHECK" get "$live" /quitDialog)" = true ] || fail "Esc with unsaved changes did not ask"
saved_before=$( [ -f "${save_path:-}" ] && sha256sum <"$save_path" || echo none)
click_widget "$live" quitDiscard
code=0
wait "$VIEWER_PID" || code=$?
VIEWER_PID=
[ "$code" -eq 0 ] || fail "the viewer exited with code $code after Quit without saving"
saved_after=$( [ -f "${save_path:-}" ] && sha256sum <"$save_path" || echo none)
[ "$saved_after" = "$saved_before" ] || fail "Quit without saving wrote the scene"

echo "PASS: the panel's sliders stay put through R and an error; Ctrl+click edits alpha; typing in a field fires no shortcut; shipped scenes are saved elsewhere; H hides the panel; quitting with unsaved changes asks"
