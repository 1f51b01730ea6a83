#!/usr/bin/env bash
# One command to build and run the whole test suite: installs missing packages, builds
# (Release with assertions on) and runs every test with CTest.
# SOFTBODY_SANITIZE=1 builds into build/sanitize with AddressSanitizer + UBSan instead.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
if [ "${SOFTBODY_SANITIZE:-0}" = 1 ]; then
  dir="$root/build/sanitize"; flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DSOFTBODY_SANITIZE=ON)
  export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  export LSAN_OPTIONS="suppressions=$root/scripts/lsan.supp:print_suppressions=0"
else
  dir="$root/build/test"; flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo)
fi
cmake -S "$root" -B "$dir" "${flags[@]}" >/dev/null
cmake --build "$dir" -j"$(nproc)"
cd "$dir" && ctest --output-on-failure -j"$(nproc)" --timeout 600
