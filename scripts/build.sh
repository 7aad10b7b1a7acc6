#!/usr/bin/env bash
# Installs the dependencies (Debian packages, idempotent) and builds everything into build/.
# usage: build.sh [extra cmake configure args...]
#   env UAVSIM_BUILD_DIR: another build directory
#   env UAVSIM_BUILD_TARGETS="T1 T2": build only these targets (and what they need), after installing only
#       the packages they need (install_deps.sh --demo): ./scripts/demo.sh's fast path
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
targets=()
if [ -n "${UAVSIM_BUILD_TARGETS:-}" ]; then
  read -r -a targets <<<"$UAVSIM_BUILD_TARGETS"
  targets=(--target "${targets[@]}")
  "$root/scripts/install_deps.sh" --demo
else
  "$root/scripts/install_deps.sh"
fi
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
cmake --build "$build" -j "$(nproc)" "${targets[@]}"
