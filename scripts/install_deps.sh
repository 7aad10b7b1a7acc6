#!/usr/bin/env bash
# Installs every build and test dependency of uavsim from Debian packages (and node-mavlink from npm,
# the independent MAVLink peer used by interop tests). Idempotent: packages already present are skipped,
# so the README's commands can call it every time.
set -euo pipefail
# usage: install_deps.sh [--demo]
#   --demo  only what configuring and building the demo's programs (./scripts/demo.sh) needs: the
#           compiler, CMake, the libraries uavsim-server and the missions link, and the tests' and
#           benches' headers (small; the configuration looks for them)
#   (none)  also what only the tests use: clang with its sanitizer runtimes, Node.js for the interop
#           peer, and the Debian packaging tools of the install tests

# the demo: build tools, the server's and missions' libraries, and what the programs run
packages=(
  build-essential cmake pkg-config ninja-build ccache
  libmujoco-dev libqhull-dev libeigen3-dev libopencv-dev libosmesa6-dev libassimp-dev
  nlohmann-json3-dev libtinyxml2-dev libgtest-dev libgmock-dev libbenchmark-dev
  python3 ffmpeg python3-matplotlib
  libegl-dev libegl-mesa0 libgl1-mesa-dri
)
# EGL rendering (--gl egl|auto): GLVND's libEGL (libegl-dev), Mesa's EGL implementation (libegl-mesa0:
# libegl1 only recommends it) and Mesa's drivers, llvmpipe among them (libgl1-mesa-dri)
if [ "${1:-}" != "--demo" ]; then
  # the tests: clang's sanitizer and libFuzzer runtimes (libclang-rt-14-dev) and llvm-symbolizer (llvm),
  # which turns sanitizer reports into file:line, are only recommended by clang: named here for
  # --no-install-recommends; dpkg-dev (dpkg-shlibdeps) and file for CPack's .deb (tests/install)
  packages+=(clang libclang-rt-14-dev llvm dpkg-dev file)
  # the ns3 radio backend (ns3/README.md): Debian's ns-3 3.37, and the -dev packages its pkg-config and
  # CMake files name (GSL, SQLite, libxml2, Python headers) but libns3-dev does not depend on
  packages+=(libns3-dev libgsl-dev libsqlite3-dev libxml2-dev libpython3-dev)
  # sweeps (tools/sweep/uavsim-sweep): GNU parallel for the local and ssh runners; SLURM (slurm-wlm:
  # slurmctld, slurmd, slurm-client) and munge for the cluster test, which starts them by hand on
  # loopback; openssh-server for the ssh runner's test (an sshd of its own on 127.0.0.1). Installing
  # them starts no service.
  packages+=(slurm-wlm munge parallel openssh-server)
  # the Python package (python/): pybind11 and Python's headers build the extension module uavsim._core
  # for Debian's python3; numpy carries its frames, pytest runs its tests (label python), OpenCV its
  # camera example; setuptools, pip and venv are what `pip install ./python` into a user's venv needs
  # offline
  packages+=(python3-dev pybind11-dev python3-pybind11 python3-numpy python3-pytest python3-opencv
             python3-setuptools python3-pip python3-venv)
  # node and npm: the machine's own Node.js is used when present (its npm may not come from Debian)
  command -v node >/dev/null 2>&1 || packages+=(nodejs)
  command -v npm >/dev/null 2>&1 || packages+=(npm)
fi

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
[ "${1:-}" != "--demo" ] || exit 0
here=$(cd "$(dirname "$0")/.." && pwd)
if [ -f "$here/tests/interop/package.json" ] && [ ! -d "$here/tests/interop/node_modules" ]; then
  echo "install_deps: npm install in tests/interop"
  (cd "$here/tests/interop" && npm install --no-audit --no-fund --silent)
fi
