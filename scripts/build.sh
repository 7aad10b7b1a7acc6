#!/usr/bin/env bash
# Installs the dependencies (Debian packages, idempotent) and builds everything into build/.
# usage: build.sh [extra cmake configure args...]   env UAVSIM_BUILD_DIR: another build directory
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
"$root/scripts/install_deps.sh"
generator=()
command -v ninja >/dev/null 2>&1 && generator=(-G Ninja)
# ccache, when present, makes rebuilds in other checkouts of the same tree cheap (paths relative to the root)
launcher=()
if command -v ccache >/dev/null 2>&1; then
  export CCACHE_BASEDIR="$root"
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
build="${UAVSIM_BUILD_DIR:-$root/build}"
cmake -S "$root" -B "$build" "${generator[@]}" "${launcher[@]}" -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build "$build" -j "$(nproc)"
