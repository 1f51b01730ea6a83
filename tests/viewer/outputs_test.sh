#!/usr/bin/env bash
# Outputs asked for on the command line that cannot be written (a folder that does not exist)
# make the program exit non-zero and name the file, windowed (Xvfb) and headless.
# usage: outputs_test.sh SOFTBODY CHECK WORKDIR
SOFTBODY=$1 CHECK=$2 WORK=$3
source "$(dirname "$0")/common.sh"
enter_xvfb "$@"

missing=$WORK/no_such_folder
rm -rf "$missing"

# expect_failure WHAT COMMAND...: COMMAND exits with code 1 and its output names $missing.
expect_failure() {
  local what=$1 code=0
  shift
  "$@" >"$WORK/out.txt" 2>&1 </dev/null || code=$?
  cat "$WORK/out.txt"
  [ "$code" -eq 1 ] || fail "$what: exit code $code, expected 1"
  grep -q "$missing" "$WORK/out.txt" || fail "$what: the message does not name the file"
}

expect_failure "windowed --screenshot" \
  "$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --frames 3 --screenshot "$missing/shot.png"
expect_failure "windowed --stats" \
  "$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --frames 3 --stats "$missing/stats.json"
expect_failure "headless --stats" env -u DISPLAY \
  "$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --frames 3 --stats "$missing/stats.json"
[ ! -e "$missing" ] || fail "a folder was created"

# The same outputs into a folder that exists: written, exit 0.
code=0
"$SOFTBODY" ${SCENE_ARGS[@]+"${SCENE_ARGS[@]}"} --frames 3 --screenshot "$WORK/shot.png" \
  --stats "$WORK/stats.json" >"$WORK/out.txt" 2>&1 </dev/null || code=$?
[ "$code" -eq 0 ] || { cat "$WORK/out.txt"; fail "exit code $code with writable outputs"; }
[ -s "$WORK/shot.png" ] && [ -s "$WORK/stats.json" ] || fail "the outputs were not written"
echo "PASS: unwritable outputs exit 1 naming the file; writable ones are written"
