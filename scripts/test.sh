#!/usr/bin/env bash
# One command to build and run the whole test suite: installs missing packages, builds
# (RelWithDebInfo: optimised, assertions on, line-table debug info: -g1 gives every stack trace
# its file and line at a sixth less compile time and a third of the object size of -g) and runs
# every test with CTest.
#   SOFTBODY_SANITIZE=1  builds with clang into build/sanitize with AddressSanitizer + UBSan
#                        instead, the fuzz targets as libFuzzer programs among them (their
#                        regression inputs are replayed as tests; scripts/fuzz.sh then fuzzes
#                        with this build instead of compiling everything once more);
#   SOFTBODY_TSAN=1      builds everything (library, app with viewer, tests) with clang and
#                        ThreadSanitizer into build/tsan, warnings as errors (the second
#                        compiler: CI's one clang build of everything) and without precompiled
#                        headers, and runs all but the viewer and soak tests; the results,
#                        golden hash included, are GCC's;
#   SOFTBODY_SOAK=1      also runs the soak tests (CTest label "soak", ~2.5 min on 2 cores;
#                        CI runs them in its GCC stage, see .ci/run).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
labels=(-LE soak)
[ "${SOFTBODY_SOAK:-0}" = 1 ] && labels=()
if [ "${SOFTBODY_SANITIZE:-0}" = 1 ]; then
  # clang: GCC 12's UBSan instrumentation made this build ~3× slower to compile (contact_solver.cpp
  # 57 s against clang's 11 s), which took CI over its time budget.
  dir="$root/build/sanitize"
  # No benchmarks: never run here, and the TSan build compiles them with clang -Werror.
  flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DSOFTBODY_SANITIZE=ON -DCMAKE_CXX_COMPILER=clang++
         -DSOFTBODY_BUILD_BENCHMARKS=OFF -DSOFTBODY_FUZZ=ON)
  export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  export LSAN_OPTIONS="suppressions=$root/scripts/lsan.supp:print_suppressions=0"
elif [ "${SOFTBODY_TSAN:-0}" = 1 ]; then
  dir="$root/build/tsan"
  # Without the precompiled headers (CMakeLists.txt, SOFTBODY_PCH): every other build has them,
  # and a file that forgot an include of Eigen or the standard library compiles there all the
  # same. This build catches it, for about two minutes more of CI (stop 53: 7:21 -> 10:35 for
  # the stage, part of it a slow phase of the VM).
  flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DSOFTBODY_TSAN=ON
         -DCMAKE_CXX_COMPILER=clang++ -DSOFTBODY_PCH=OFF)
  export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:history_size=4:suppressions=$root/scripts/tsan.supp"
  # The Xvfb viewer tests are built but not run here: they time real frames, which TSan's
  # slowdown turns into timeouts. viewer_step_thread (label "threads") does run: the viewer's own
  # thread, the step beside the drawing, is checked here.
  labels=(-LE "soak|viewer")
else
  # No benchmarks here either: they are not tests, and CI's TSan build compiles every one of them
  # with clang -Werror (a Release build for measuring builds them with GCC).
  dir="$root/build/test"; flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DSOFTBODY_BUILD_BENCHMARKS=OFF)
fi
cmake -S "$root" -B "$dir" "${flags[@]}" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1" >/dev/null
cmake --build "$dir" -j"$(nproc)"
cd "$dir" && ctest --output-on-failure -j"$(nproc)" --timeout 2400 "${labels[@]}"
