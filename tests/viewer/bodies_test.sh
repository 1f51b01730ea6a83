#!/usr/bin/env bash
# Bodies added and removed while the viewer runs (xdotool, inside Xvfb): a mesh file named in
# the Scene file section is added as a soft body with an automatic cage made on another thread
# (the same path a file dropped on the window takes), falls and comes to rest above the ground; body 0's duplicate and
# remove buttons add a copy and take the body away.
# usage: bodies_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
enter_xvfb "$@"

live=$WORK/live.json
cd "$WORK"
start_live_viewer "$live"
n0=$("$CHECK" get "$live" /bodyCount)
mesh=$(dirname "$("$CHECK" get "$live" /scenePath)")/../meshes/bunny_cage.obj
[ -f "$mesh" ] || fail "no mesh to add at $mesh"

click_widget "$live" sceneHeader
next_frames "$live" 5
click_widget "$live" addMeshPath
replace_text "$mesh"
click_widget "$live" addMesh
# The cage is made on another thread while the scene runs: the body comes some frames later.
for try in $(seq 1 60); do
  next_frames "$live" 5
  [ "$("$CHECK" get "$live" /bodyCount)" = $((n0 + 1)) ] && break
done
[ "$("$CHECK" get "$live" /addingBodies)" = 0 ] || fail "a body is still being added"
status=$("$CHECK" get "$live" /status)
echo "status: $status"
[ "$("$CHECK" get "$live" /bodyCount)" = $((n0 + 1)) ] || fail "no body was added ($("$CHECK" get "$live" /error))"
[ "$("$CHECK" get "$live" /bodies/$n0/name)" = bunny_cage ] || fail "the new body is not named after its file"
case "$status" in *"automatic cage"*) ;; *) fail "the status does not say the body got an automatic cage" ;; esac

# It falls onto the scene and comes to rest above the ground.
# Its start height: where it was placed (it may have landed before the first look, on a loaded
# machine).
y0=$("$CHECK" get "$live" /bodies/$n0/startCentre | cut -d' ' -f2)
next_frames "$live" 300
y1=$("$CHECK" get "$live" /bodies/$n0/centre | cut -d' ' -f2)
next_frames "$live" 60
y2=$("$CHECK" get "$live" /bodies/$n0/centre | cut -d' ' -f2)
echo "added body's centre height: $y0 -> $y1 -> $y2 m"
awk -v a="$y0" -v b="$y1" 'BEGIN { exit !(b < a - 0.1) }' || fail "the added body did not fall"
awk -v b="$y2" 'BEGIN { exit !(b > 0) }' || fail "the added body is below the ground"
awk -v b="$y1" -v c="$y2" 'BEGIN { d = c - b; exit !(d < 0.01 && d > -0.01) }' ||
  fail "the added body is not at rest ($y1 -> $y2 m within one second)"

# Duplicate and remove body 0 (the Scene file section is closed again so its buttons are on
# screen).
click_widget "$live" sceneHeader
next_frames "$live" 5
name0=$("$CHECK" get "$live" /bodies/0/name)
click_widget "$live" duplicate0
next_frames "$live" 5
[ "$("$CHECK" get "$live" /bodyCount)" = $((n0 + 2)) ] || fail "duplicate did not add a body"
[ "$("$CHECK" get "$live" /bodies/$((n0 + 1))/name)" = "$name0 copy" ] || fail "the copy is not named '$name0 copy'"
click_widget "$live" remove0
next_frames "$live" 5
[ "$("$CHECK" get "$live" /bodyCount)" = $((n0 + 1)) ] || fail "remove did not take a body away"
[ "$("$CHECK" get "$live" /bodies/0/name)" != "$name0" ] || fail "body 0 is still there"
[ -z "$("$CHECK" get "$live" /error)" ] || fail "error: $("$CHECK" get "$live" /error)"
echo "PASS: a mesh added as a body falls and rests; duplicate and remove work"
