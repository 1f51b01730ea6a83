# Shared helpers of the viewer test scripts (sourced). Needs SOFTBODY, CHECK and WORK set.
set -euo pipefail

XVFB_SERVER_ARGS="-screen 0 1280x720x24"
# The scene: the default one unless VIEWER_TEST_SCENE names another (for trying other scenes).
SCENE_ARGS=()
if [ -n "${VIEWER_TEST_SCENE:-}" ]; then SCENE_ARGS=("$VIEWER_TEST_SCENE"); fi

# Re-runs the calling script (once) inside its own Xvfb display, with a clean work folder.
# Call as `enter_xvfb "$@"` right after sourcing this file.
enter_xvfb() {
  if [ "${INNER:-0}" != 1 ]; then
    mkdir -p "$WORK"
    rm -f "$WORK"/*.json
    INNER=1 exec xvfb-run -a -s "$XVFB_SERVER_ARGS" bash "$0" "$@" </dev/null
  fi
}

fail() {
  echo "FAIL: $*" >&2
  exit 1
}

# wait_for_frame STATS N [TIMEOUT_S]: waits until the stats file reports frame >= N.
wait_for_frame() {
  local stats=$1 want=$2 timeout=${3:-60} waited=0 frame
  while :; do
    if [ -s "$stats" ]; then
      frame=$("$CHECK" get "$stats" /frame 2>/dev/null || echo 0)
      [ "$frame" -ge "$want" ] && return 0
    fi
    if [ -n "${VIEWER_PID:-}" ] && ! kill -0 "$VIEWER_PID" 2>/dev/null; then
      fail "the viewer exited before frame $want (see $WORK/viewer.log)"
    fi
    sleep 0.1
    waited=$((waited + 1))
    [ "$waited" -ge $((timeout * 10)) ] && fail "timed out waiting for frame $want in $stats"
  done
}

# copy_stats STATS OUT: copies the stats file the viewer is rewriting. The viewer replaces it
# by renaming a new file over it; cp noticed that mid-copy now and then and skipped the file
# ("replaced while being copied", a flaky failure), while one open descriptor reads one whole
# version.
copy_stats() {
  cat "$1" >"$2" || fail "cannot copy $1"
}

# snapshot STATS N OUT: waits for frame >= N and copies the stats file to OUT.
snapshot() {
  wait_for_frame "$1" "$2"
  copy_stats "$1" "$3"
}

# start_live_viewer STATS [OPTION...]: starts the viewer on the test's scene in the background,
# running (nearly) for ever and writing STATS every 3 frames; it is killed when the script exits.
# Returns once frame 10 is reported.
start_live_viewer() {
  local stats=$1
  shift
  "$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --frames 100000 --stats "$stats" --stats-every 3 \
    "$@" >"$WORK/viewer.log" 2>&1 &
  VIEWER_PID=$!
  trap '[ -n "${VIEWER_PID:-}" ] && kill "$VIEWER_PID" 2>/dev/null || true' EXIT
  wait_for_frame "$stats" 10
}

# finish_viewer: waits for the background viewer to exit and checks its exit code.
finish_viewer() {
  local code=0
  wait "$VIEWER_PID" || code=$?
  VIEWER_PID=
  [ "$code" -eq 0 ] || { cat "$WORK/viewer.log" >&2; fail "the viewer exited with code $code"; }
}

# click_widget STATS NAME: a real mouse click on a panel control recorded in the stats file.
# widget_point STATS NAME: prints the click point of a recorded control. The stats of a frame
# list the controls its panel drew, and the panel is drawn before the frame's changes apply (a
# re-bind, a removed body), so a control that a change brings appears a frame later: waits up
# to 30 frames for it.
widget_point() {
  local tries=0
  until "$CHECK" click-point "$1" "$2" 2>/dev/null; do
    tries=$((tries + 1))
    [ "$tries" -le 10 ] || fail "control $2 not found in $1"
    next_frames "$1" 3
  done
}

click_widget() {
  local x y
  read -r x y < <(widget_point "$1" "$2") || fail "control $2 not found in $1"
  xdotool mousemove "$x" "$y"
  sleep 0.15
  xdotool click 1
  sleep 0.15
}

# replace_text TEXT: selects all in the focused ImGui text field and types TEXT. Keys are held
# for a moment: ImGui 1.86 polls key state once per frame.
replace_text() {
  xdotool keydown ctrl keydown a
  sleep 0.15
  xdotool keyup a keyup ctrl
  sleep 0.1
  xdotool type --delay 15 "$1"
  sleep 0.1
}

# ctrl_click_type STATS WIDGET TEXT: Ctrl+click on a recorded slider (ImGui turns it into a text
# field), replace its text with TEXT and press Enter.
ctrl_click_type() {
  local x y
  read -r x y < <(widget_point "$1" "$2") || fail "control $2 not found in $1"
  xdotool mousemove "$x" "$y"
  sleep 0.15
  xdotool keydown ctrl
  sleep 0.1
  xdotool click 1
  sleep 0.15
  xdotool keyup ctrl
  sleep 0.1
  replace_text "$3"
  xdotool keydown Return  # held for a moment, as in replace_text
  sleep 0.15
  xdotool keyup Return
}

# next_frame STATS [N]: waits N (default 10) frames past the current one.
next_frames() {
  local now
  now=$("$CHECK" get "$1" /frame)
  wait_for_frame "$1" $((now + ${2:-10}))
}

# Windowed runs: Mesa's llvmpipe driver leaves a few allocations behind when it is unloaded at
# exit (LeakSanitizer reports them as "<unknown module>" leaks in sanitizer builds), so leak
# checking is off for them. The headless test keeps it on.
ASAN_OPTIONS="${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0"
export ASAN_OPTIONS
