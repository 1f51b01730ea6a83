#!/usr/bin/env bash
# The default scene is drawn: in a screenshot after N frames, each body's projected screen
# bounds (from the stats file) differ clearly from the same frame rendered without the bodies.
# Stepping on a second thread while drawing (the default) and stepping first (--no-overlap)
# reach the same state bit for bit.
# usage: render_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
mkdir -p "$WORK"
rm -f "$WORK"/*.png "$WORK"/*.json
run() {
  xvfb-run -a -s "$XVFB_SERVER_ARGS" "$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --frames 90 --size 1280x720 "$@" </dev/null
}
run --screenshot "$WORK/shot.png" --stats "$WORK/shot.json" >"$WORK/shot.log" 2>&1 ||
  { cat "$WORK/shot.log"; fail "viewer run failed"; }
run --screenshot "$WORK/empty.png" --stats "$WORK/empty.json" --hide-bodies >"$WORK/empty.log" 2>&1 ||
  { cat "$WORK/empty.log"; fail "viewer run without bodies failed"; }
run --no-overlap --stats "$WORK/serial.json" >"$WORK/serial.log" 2>&1 ||
  { cat "$WORK/serial.log"; fail "viewer run with --no-overlap failed"; }
"$CHECK" same-state "$WORK/shot.json" "$WORK/serial.json" ||
  fail "stepping while drawing reached another state than stepping first"
cat "$WORK/shot.log"
[ -s "$WORK/shot.png" ] || fail "no screenshot written"
"$CHECK" visible "$WORK/shot.png" "$WORK/empty.png" "$WORK/shot.json" || fail "a body is not visible"
echo "PASS: every body is visible in $WORK/shot.png"
