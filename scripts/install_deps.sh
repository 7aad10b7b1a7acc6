#!/usr/bin/env bash
# Installs every build and test dependency of uavsim from Debian packages (and node-mavlink from npm,
# the independent MAVLink peer used by interop tests). Idempotent: packages already present are skipped,
# so the README's commands can call it every time.
set -euo pipefail

packages=(
  build-essential cmake pkg-config ninja-build
  libmujoco-dev libqhull-dev libeigen3-dev libopencv-dev libosmesa6-dev libassimp-dev
  nlohmann-json3-dev libtinyxml2-dev libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev llvm python3 ffmpeg ccache python3-matplotlib
  libegl-dev libegl-mesa0 libgl1-mesa-dri
  libns3-dev libgsl-dev libsqlite3-dev libxml2-dev libpython3-dev
)
# the ns3 radio backend (ns3/README.md): Debian's ns-3 3.37, and the -dev packages its pkg-config and CMake
# files name (GSL, SQLite, libxml2, Python headers) but libns3-dev does not depend on
# EGL rendering (--gl egl|auto): GLVND's libEGL (libegl-dev), Mesa's EGL implementation (libegl-mesa0:
# libegl1 only recommends it) and Mesa's drivers, llvmpipe among them (libgl1-mesa-dri)
# clang's sanitizer and libFuzzer runtimes (libclang-rt-14-dev) and llvm-symbolizer (llvm), which turns
# sanitizer reports into file:line, are only recommended by clang: named here for --no-install-recommends
# node and npm: the machine's own Node.js is used when present (its npm may not come from Debian)
command -v node >/dev/null 2>&1 || packages+=(nodejs)
command -v npm >/dev/null 2>&1 || packages+=(npm)

# pick the packages that are not installed yet
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if ((${#missing[@]})); then
  sudo_cmd=()
  if [ "$(id -u)" -ne 0 ]; then sudo_cmd=(sudo); fi
  echo "install_deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -qq
  "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
else
  echo "install_deps: Debian packages present"
fi

# node-mavlink for the interop tests, pinned in tests/interop/package.json
here=$(cd "$(dirname "$0")/.." && pwd)
if [ -f "$here/tests/interop/package.json" ] && [ ! -d "$here/tests/interop/node_modules" ]; then
  echo "install_deps: npm install in tests/interop"
  (cd "$here/tests/interop" && npm install --no-audit --no-fund --silent)
fi
