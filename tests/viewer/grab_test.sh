#!/usr/bin/env bash
# The stats file's grab pixels are where a real click grabs that body, in a scene where bodies
# hide each other (the pile, paused once the bodies have fallen into the pen): for every body
# with a grab pixel, a mouse press there (xdotool, inside Xvfb) must start a drag of exactly that
# body. The viewer picks the nearest hit on all drawn meshes; the stats file finds its pixels
# with a cheaper, conservative test (a triangle of the body's own mesh and the other bodies'
# cages), which this checks end to end.
# usage: grab_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
enter_xvfb "$@"

start_live_viewer "$WORK/live.json"
snapshot "$WORK/live.json" 150 "$WORK/fallen.json"
xdotool key space
next_frames "$WORK/live.json" 10
copy_stats "$WORK/live.json" "$WORK/paused.json"
[ "$("$CHECK" get "$WORK/paused.json" /paused)" = true ] || fail "space did not pause"
count=$("$CHECK" get "$WORK/paused.json" /bodyCount)
found=0
for ((b = 0; b < count; b++)); do
  read -r x y < <("$CHECK" grab-pixel "$WORK/paused.json" "$b" 2>/dev/null) || continue
  found=$((found + 1))
  xdotool mousemove "$x" "$y"
  sleep 0.15
  xdotool mousedown 1
  # The stats file is written every 3 frames, after the frame's events: the press shows in a
  # later write, not necessarily the next one.
  for try in $(seq 1 10); do
    next_frames "$WORK/live.json" 3
    copy_stats "$WORK/live.json" "$WORK/held$b.json"
    [ "$("$CHECK" get "$WORK/held$b.json" /drag/active)" = true ] && break
  done
  xdotool mouseup 1
  next_frames "$WORK/live.json" 3
  [ "$("$CHECK" get "$WORK/held$b.json" /drag/active)" = true ] ||
    fail "a press at body $b's grab pixel $x,$y started no drag"
  held=$("$CHECK" get "$WORK/held$b.json" /drag/body)
  [ "$held" = "$b" ] || fail "a press at body $b's grab pixel $x,$y grabbed body $held"
  echo "body $b: grabbed at $x,$y"
done
# Hidden bodies may have none, but most of a pile is in view.
[ "$found" -ge $((count * 3 / 4)) ] || fail "only $found of $count bodies have a grab pixel"
echo "PASS: $found of $count bodies were grabbed at their grab pixels"
