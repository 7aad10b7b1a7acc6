#!/usr/bin/env bash
# The README's test command: dependencies, build, then every test (unit, system, scenario) through ctest.
#
#   scripts/test.sh [ctest args...]              the normal build (build/) and its tests
#   scripts/test.sh --sanitize [ctest args...]   ASan + UBSan build (build-sanitize/, clang when present so
#                                                the fuzz targets build too, benches off) and its tests,
#                                                with LeakSanitizer suppressions for leaks outside our code
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)

# ctest with its output on the console, then the tests that failed a try and passed a retry
# (--repeat until-pass:N hides them otherwise): each is a flake to find and fix, so they are named
run_ctest() {
  local log rc flaky
  log=$(mktemp)
  set +e
  ctest --output-on-failure -j "$(nproc)" "$@" 2>&1 | tee "$log"
  rc=${PIPESTATUS[0]}
  set -e
  flaky=$(awk '$2 == "Test" && $3 ~ /^#[0-9]+:$/ {
                 if ($0 ~ /Passed/) passed[$4] = 1; else failed[$4] = 1
               }
               END { for (t in failed) if (t in passed) print t }' "$log" | sort)
  rm -f "$log"
  if [ -n "$flaky" ]; then
    echo "test.sh: these tests passed only on a retry (flaky: find why they depend on load):"
    printf '  %s\n' $flaky
  fi
  return "$rc"
}

if [ "${1:-}" != "--sanitize" ]; then
  "$root/scripts/build.sh"
  cd "$root/build"
  run_ctest "$@"
  exit
fi
shift

build="$root/build-sanitize"
compilers=()
lines=-g1  # GCC's nearest to line tables only
if command -v clang++ >/dev/null 2>&1 && command -v clang >/dev/null 2>&1; then
  compilers=(-DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++)
  lines=-gline-tables-only
fi
# -O2 keeps the long scenarios inside their time limits; line tables alone give reports with file:line
# at a fraction of full -g's compile and link time
UAVSIM_BUILD_DIR="$build" "$root/scripts/build.sh" "${compilers[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 $lines -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O2 $lines -DNDEBUG" \
  -DUAVSIM_SANITIZE=ON -DUAVSIM_BUILD_BENCH=OFF

export ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:detect_stack_use_after_return=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export LSAN_OPTIONS="suppressions=$root/scripts/lsan.supp:print_suppressions=0"
cd "$build"
run_ctest "$@"
