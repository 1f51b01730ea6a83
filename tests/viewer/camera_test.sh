#!/usr/bin/env bash
# The orbit camera under real mouse input (xdotool, inside Xvfb): right drag orbits (yaw
# changes, distance kept), the wheel zooms (distance shrinks), Shift + right drag pans (target
# moves, angles kept), and the same right drag over the panel leaves the camera alone.
# usage: camera_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
enter_xvfb "$@"
live=$WORK/live.json
start_live_viewer "$live" --paused

camera() { "$CHECK" get "$live" "/camera/$1"; }
right_drag() {  # right_drag X Y DX [MODIFIER]
  xdotool mousemove "$1" "$2"
  sleep 0.1
  [ -n "${4:-}" ] && xdotool keydown "$4"
  xdotool mousedown 3
  for s in 1 2 3 4 5 6; do
    xdotool mousemove $(($1 + $3 * s / 6)) "$2"
    sleep 0.03
  done
  xdotool mouseup 3
  [ -n "${4:-}" ] && xdotool keyup "$4"
  next_frames "$live" 5
}

yaw0=$(camera yaw) distance0=$(camera distance) target0=$(camera target)
right_drag 100 400 150   # over the panel: ImGui's, not the camera's
[ "$(camera yaw)" = "$yaw0" ] || fail "a drag over the panel orbited the camera"

right_drag 800 400 150
yaw1=$(camera yaw)
[ "$yaw1" != "$yaw0" ] || fail "right drag did not orbit"
[ "$(camera distance)" = "$distance0" ] || fail "orbiting changed the distance"
echo "orbit: yaw $yaw0 -> $yaw1"

xdotool mousemove 800 400 click 4 click 4 click 4
next_frames "$live" 5
distance1=$(camera distance)
awk -v a="$distance1" -v b="$distance0" 'BEGIN { exit !(a < b) }' || fail "wheel did not zoom in"
echo "zoom: distance $distance0 -> $distance1"

right_drag 800 400 150 shift
target1=$(camera target)
[ "$target1" != "$target0" ] || fail "Shift + right drag did not pan"
[ "$(camera yaw)" = "$yaw1" ] || fail "panning changed the view direction"
echo "pan: target $target0 -> $target1"
echo "PASS: orbit, zoom and pan follow the mouse; the panel keeps its own input"
