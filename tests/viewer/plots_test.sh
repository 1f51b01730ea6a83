#!/usr/bin/env bash
# The solver plots (xdotool, inside Xvfb): scrolled to the end of the panel, the "Plots" header
# opens plots of the last 10 s; one sample per frame (at most 600); the scene's kinetic energy is
# positive while the bodies fall and exactly 0 once every body sleeps; a line is drawn across the
# kinetic-energy plot in a screenshot of the screen (saved as WORK/plots.png to look at).
# usage: plots_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
enter_xvfb "$@"

live=$WORK/live.json
cd "$WORK"
start_live_viewer "$live" --paused  # runs once the plots are open (space)
plot() { "$CHECK" get "$live" "/plots/$1"; }

# scroll_panel: the mouse wheel over the panel, down to its end.
scroll_panel() {
  xdotool mousemove 150 400
  sleep 0.15
  for _ in $(seq 20); do
    xdotool click 5
    sleep 0.03
  done
  next_frames "$live" 5
}
scroll_panel
click_widget "$live" plotsHeader
next_frames "$live" 5
scroll_panel
[ "$(plot samples)" = 0 ] || fail "samples taken while paused"
xdotool mousemove 900 200
sleep 0.15
xdotool key space
next_frames "$live" 30

early=$(plot kinetic)
samples=$(plot samples)
echo "kinetic energy at frame $("$CHECK" get "$live" /frame): $early J, $samples samples"
awk -v e="$early" 'BEGIN { exit !(e > 0) }' || fail "no kinetic energy plotted while the bodies fall"
[ "$samples" -gt 10 ] || fail "only $samples samples"

next_frames "$live" 30
xwd -root -silent | convert xwd:- "$WORK/plots.png"
copy_stats "$live" "$WORK/plots.json"
"$CHECK" plotted "$WORK/plots.png" "$WORK/plots.json" plotKinetic || fail "no line in the kinetic-energy plot"

# Every body asleep (the default scene rests within ~5 s): nothing moves, exactly 0 J; the
# history stays within its 600 samples.
for _ in $(seq 40); do
  [ "$(plot kinetic)" = 0 ] && break
  next_frames "$live" 30
done
[ "$(plot kinetic)" = 0 ] || fail "kinetic energy $(plot kinetic) J after $("$CHECK" get "$live" /simTime) s"
next_frames "$live" 30
samples=$(plot samples)
echo "at rest from t = $("$CHECK" get "$live" /simTime) s or earlier; $samples samples"
[ "$samples" -le 600 ] || fail "$samples samples kept (at most 600)"
kill "$VIEWER_PID"
VIEWER_PID=
echo "PASS: plots open from the panel, sample every frame, show the kinetic energy falling to 0 at rest, and draw their line"
