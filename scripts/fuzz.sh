#!/usr/bin/env bash
# Fuzzes every reader of outside bytes with libFuzzer under AddressSanitizer + UBSan: the scene
# parser, the OBJ/OFF/PLY/STL readers, the bind cache loader and the frame reader
# (tests/fuzz/). Uses the fuzz programs of the ASan test build (build/sanitize, made by
# SOFTBODY_SANITIZE=1 scripts/test.sh, as CI's stage before this one) when it has them, else
# builds them with clang into build/fuzz; writes seed corpora from the shipped assets, then runs
# each target for SECONDS (default 60; CI uses its own budget, see .ci/run).
#
#   ./scripts/fuzz.sh [SECONDS] [TARGET...]
#
# The corpora grow in the build folder's corpus/<target>/ and are kept between runs, so a longer
# maintainer run simply continues, e.g. an hour per target overnight:
#   ./scripts/fuzz.sh 3600
# A crash stops the run and leaves the input in the build folder's artifacts/; after fixing the cause,
# copy it to tests/fuzz/regressions/<target>/ (every test build replays those inputs as the
# CTest tests fuzz_regressions.<target>).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install-deps.sh"
seconds=${1:-60}
shift || true
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=(scene mesh_obj mesh_off mesh_ply mesh_stl bind_cache frame)
dir="$root/build/sanitize"
if ! grep -qx "SOFTBODY_FUZZ:BOOL=ON" "$dir/CMakeCache.txt" 2>/dev/null; then
  dir="$root/build/fuzz"
  cmake -S "$root" -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_COMPILER=clang++ -DSOFTBODY_FUZZ=ON -DSOFTBODY_SANITIZE=ON \
    -DSOFTBODY_BUILD_TESTS=OFF -DSOFTBODY_BUILD_VIEWER=OFF >/dev/null
fi
echo "fuzz: programs of $dir"
cmake --build "$dir" -j"$(nproc)" --target make_fuzz_seeds "${targets[@]/#/fuzz_}"
export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export LSAN_OPTIONS="suppressions=$root/scripts/lsan.supp:print_suppressions=0"
seeds="$dir/fuzz-seeds"
rm -rf "$seeds"
"$dir/tests/fuzz/make_fuzz_seeds" "$seeds" >/dev/null
mkdir -p "$dir/artifacts"
for t in "${targets[@]}"; do
  corpus="$dir/corpus/$t"
  mkdir -p "$corpus"
  before=$(find "$corpus" -type f | wc -l)
  log="$dir/fuzz_$t.log"
  echo "fuzz: $t for ${seconds}s (corpus $before files + seeds)"
  if ! "$dir/tests/fuzz/fuzz_$t" "$corpus" "$seeds/$t" "$root/tests/fuzz/regressions/$t" \
      -max_total_time="$seconds" -timeout=30 -rss_limit_mb=4096 -max_len=262144 \
      -print_final_stats=1 -artifact_prefix="$dir/artifacts/$t-" >"$log" 2>&1; then
    tail -n 60 "$log"
    echo "fuzz: $t FAILED (input in $dir/artifacts/)" >&2
    exit 1
  fi
  after=$(find "$corpus" -type f | wc -l)
  runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  cov=$(grep -o 'cov: [0-9]* ft: [0-9]*' "$log" | tail -n 1 || echo "?")
  added=$(grep -o 'stat::new_units_added: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo "?")
  initcov=$(grep -o 'INITED cov: [0-9]* ft: [0-9]*' "$log" | head -n 1 | sed 's/INITED //' || echo "?")
  echo "fuzz: $t ok: $runs executions, coverage after seeds ($initcov) -> end ($cov)," \
       "$added new inputs, corpus $before -> $after files"
done
