#!/usr/bin/env bash
# Embeddings in the viewer (issue 14), driven with real mouse events (xdotool, inside Xvfb) on
# tests/viewer/embedding_scene.json: body 0 "switch" (a cage body), body 1 "crush", body 2
# "lattice" (a B-spline lattice body, 6x6x6 nodes). Body 1 has no shape to keep (alpha 0): it
# lands flat on the floor, its cage's vertices crossing each other, so its map folds (45 of
# 339 samples in `softbody run --fold-check` at 2 s).
#  1. The embedding combo of body 0 switches it from mvc to harmonic: the stats report the new
#     method and the weights in use (boundKind) are harmonic too.
#  2. A refused switch (a resolution typed out of range) shows the error, scrolled into view and
#     naming the body once, and keeps the old binding.
#  3. The fold check names body 1 with its folded samples, and the screenshot shows the fold
#     tint on body 1 (none before the check was ticked).
#  4. A surface drag on the lattice body moves it with a point constraint over the lattice
#     weights: at most the 64 nodes of one B-spline span of the 216.
#  5. Green: accepted (suzanne lies inside its cage: method and weights green), and the fold
#     check, still on, watches the Green map like the others: no error, body 0 not folded.
#  6. Save writes the new "embedding" of body 0.
# usage: embedding_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
enter_xvfb "$@"

SCENE_ARGS=("$(cd "$(dirname "$0")" && pwd)/embedding_scene.json")
export SOFTBODY_CACHE_DIR=$WORK/cache  # binds made here stay here
rm -rf "$SOFTBODY_CACHE_DIR" "$WORK"/*.png
live=$WORK/live.json
cd "$WORK"  # the Screenshot button writes softbody_screenshot.png here
start_live_viewer "$live"

get() { "$CHECK" get "$live" "$1"; }
# wait_until POINTER VALUE [FRAMES]: polls the stats until POINTER reads VALUE (a bind of
# harmonic coordinates blocks a frame for ~0.5 s, longer on a loaded machine).
wait_until() {
  local waited=0
  until [ "$(get "$1")" = "$2" ]; do
    next_frames "$live" 3
    waited=$((waited + 1))
    [ "$waited" -le "${3:-100}" ] || fail "$1 is '$(get "$1")', expected '$2'"
  done
}
# screenshot NAME: clicks the Screenshot button and moves the PNG to $WORK/NAME.png.
screenshot() {
  rm -f softbody_screenshot.png
  click_widget "$live" screenshot
  local waited=0
  until [ -s softbody_screenshot.png ]; do
    sleep 0.1
    waited=$((waited + 1))
    [ "$waited" -le 100 ] || fail "the Screenshot button wrote no file"
  done
  sleep 0.2  # written by the viewer in one go, but give the rename a moment
  cp softbody_screenshot.png "$1.png"
  copy_stats "$live" "$1.json"
}

[ "$(get /bodies/0/embedding/method)" = mvc ] || fail "body 0 does not start with mvc"
[ "$(get /bodies/2/embedding/method)" = lattice ] || fail "body 2 is not a lattice body"
[ "$(get /foldCheck/enabled)" = false ] || fail "the fold check is on at start"

# ---- 1. switch body 0 to harmonic with the combo ----
click_widget "$live" embedding0
next_frames "$live" 5
click_widget "$live" embedding0.harmonic
wait_until /bodies/0/embedding/method harmonic
[ "$(get /bodies/0/embedding/boundKind)" = harmonic ] || fail "the stats name harmonic but the weights are $(get /bodies/0/embedding/boundKind)"
[ "$(get /bodies/0/embedding/resolution)" = 32 ] || fail "harmonic resolution is not the default 32"
[ -z "$(get /bodies/0/embedding/error)" ] || fail "an error after a good switch: $(get /bodies/0/embedding/error)"
case "$(get /status)" in
  "switch: render mesh bound with harmonic (resolution 32) in "*) ;;
  *) fail "the status bar does not report the bind: $(get /status)" ;;
esac
echo "switched body 0 to harmonic: $(get /status)"

# ---- 2. refused switches keep the old binding ----
ctrl_click_type "$live" resolution0 65
next_frames "$live" 10
wait_until /binding false
error=$(get /bodies/0/embedding/error)
echo "resolution 65: $error"
[ -n "$error" ] || fail "no error shown for resolution 65"
case "$error" in *resolution*) ;; *) fail "the error does not name the resolution: $error" ;; esac
[ "$(get /bodies/0/embedding/method)" = harmonic ] || fail "the refused bind changed the method"
[ "$(get /bodies/0/embedding/resolution)" = 32 ] || fail "the refused bind changed the resolution"
[ "$(get /bodies/0/embedding/boundKind)" = harmonic ] || fail "the refused bind changed the weights"
# The status bar names the body once; the panel, under the body's own controls, not at all.
[ "$(get /error)" = "switch: $error" ] || fail "the status bar says '$(get /error)'"
case "$error" in *switch*) fail "the panel's error repeats the body's name: $error" ;; esac
# The panel scrolled the error into view: its last line ends inside the window (720 px).
next_frames "$live" 3
bottom=$(get /widgets/embeddingError0/3)
[ "${bottom%.*}" -le 720 ] || fail "the error ends at y = $bottom, below the window"
screenshot "$WORK/refused"

# ---- 3. the fold check: body 1 folds, the panel warns, the mesh is tinted ----
screenshot "$WORK/before_folds"
untinted=$("$CHECK" tinted "$WORK/before_folds.png" "$WORK/before_folds.json" 1 0)
[ "$untinted" -lt 20 ] || fail "$untinted fold-tint pixels on body 1 before the fold check was on"
click_widget "$live" foldCheck
wait_until /foldCheck/enabled true
waited=0
until [ "$(get /bodies/1/foldedSamples)" -gt 0 ]; do
  next_frames "$live" 5
  waited=$((waited + 1))
  [ "$waited" -le 60 ] || fail "no folded samples reported for the crushed body: $(get /foldCheck)"
done
next_frames "$live" 10
[ "$(get /foldCheck/folded/0/body)" = 1 ] || fail "the first folded body is not body 1: $(get /foldCheck)"
[ "$(get /bodies/0/foldedSamples)" = 0 ] || fail "body 0 (at rest) reported as folded"
[ "$(get /foldCheck/folded/0/tintedVertices)" -gt 0 ] || fail "no render vertex tinted on body 1"
[ -n "$("$CHECK" click-point "$live" foldWarning1)" ] || fail "no fold warning on body 1's line in the panel"
[ -n "$("$CHECK" click-point "$live" foldStatus1)" ] || fail "no fold warning for body 1 in the status bar"
[ "$("$CHECK" get "$live" /widgets/foldStatus0 2>/dev/null)" = "" ] || fail "a fold warning for body 0 (at rest)"
echo "fold check: $(get /bodies/1/foldedSamples) of $(get /foldCheck/folded/0/samples) samples of body 1 folded, $(get /foldCheck/folded/0/tintedVertices) vertices tinted"
screenshot "$WORK/folds"
"$CHECK" tinted "$WORK/folds.png" "$WORK/folds.json" 1 300 >/dev/null ||
  fail "the fold tint is not visible on body 1 in $WORK/folds.png"

# ---- 4. a surface drag on the lattice body ----
next_frames "$live" 30
copy_stats "$live" "$WORK/lattice_before.json"
read -r x y < <("$CHECK" grab-pixel "$WORK/lattice_before.json" 2) || fail "no pixel hits the lattice body"
echo "grabbing the lattice body at pixel $x,$y"
xdotool mousemove "$x" "$y"
sleep 0.2
xdotool mousedown 1
for step in $(seq 1 8); do
  xdotool mousemove $((x + 12 * step)) $((y - 8 * step))
  sleep 0.05
done
next_frames "$live" 40
copy_stats "$live" "$WORK/lattice_held.json"
xdotool mouseup 1
held() { "$CHECK" get "$WORK/lattice_held.json" "$1"; }
[ "$(held /drag/active)" = true ] || fail "no active drag while the button was held"
[ "$(held /drag/body)" = 2 ] || fail "the drag grabbed body $(held /drag/body), not the lattice"
[ "$(held /drag/nearestParticle)" = false ] || fail "not a surface drag"
nodes=$(held /drag/particles)
# A B-spline point's weights: the 4x4x4 nodes of its span (fewer where a basis value is 0),
# more than one node, far fewer than the lattice's 216.
[ "$nodes" -gt 1 ] && [ "$nodes" -le 64 ] || fail "the drag holds $nodes lattice nodes (expected 2 to 64)"
"$CHECK" moved "$WORK/lattice_before.json" "$WORK/lattice_held.json" 2 0.03 ||
  fail "the lattice body did not follow the mouse"
echo "lattice drag: $nodes nodes held"

# ---- 5. green: accepted, in one step (never half switched), and fold-checked like the others
click_widget "$live" embedding0
next_frames "$live" 5
click_widget "$live" embedding0.green
next_frames "$live" 10
wait_until /binding false
method=$(get /bodies/0/embedding/method)
error=$(get /bodies/0/embedding/error)
[ -z "$error" ] || fail "green refused: $error"
[ "$method" = green ] && [ "$(get /bodies/0/embedding/boundKind)" = green ] ||
  fail "green accepted but method $method, weights $(get /bodies/0/embedding/boundKind)"
next_frames "$live" 15  # the fold check runs every 5 frames
[ "$(get /foldCheck/enabled)" = true ] || fail "the fold check went off"
[ -z "$(get /foldCheck/error)" ] || fail "the fold check stopped on the Green map: $(get /foldCheck/error)"
[ "$(get /bodies/0/foldedSamples)" = 0 ] || fail "body 0 (green, at rest) reported as folded"
echo "green accepted and fold-checked"

# ---- 6. Save writes body 0's embedding ----
click_widget "$live" sceneHeader
next_frames "$live" 5
click_widget "$live" savePath
replace_text "$WORK/saved.json"
click_widget "$live" save
next_frames "$live" 5
[ -s "$WORK/saved.json" ] || fail "Save wrote nothing: $(get /error)"
# (body 0 is harmonic or green here, so the file names it: mean value is the default, left out)
saved_method=$("$CHECK" get "$WORK/saved.json" /bodies/0/embedding/method) ||
  fail "the saved scene has no embedding for body 0"
[ "$saved_method" = "$(get /bodies/0/embedding/method)" ] ||
  fail "the saved scene's body 0 embedding is $saved_method, the viewer's $(get /bodies/0/embedding/method)"

kill "$VIEWER_PID" 2>/dev/null || true
wait "$VIEWER_PID" 2>/dev/null || true
VIEWER_PID=
echo "PASS: embedding switch (and refusals), fold warning and tint, lattice drag, save"
