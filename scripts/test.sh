#!/usr/bin/env bash
# The README's test command: dependencies, build, then every test (unit, system, scenario) through ctest.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/build.sh"
cd "$root/build"
ctest --output-on-failure -j "$(nproc)" "$@"
