"""pip install ./python: the extension module is built by the project's CMake (a client-only build: no
MuJoCo, no server), for the interpreter pip runs under, and put into the package. Offline: needs cmake, a
C++20 compiler, Eigen, nlohmann-json, OpenCV (for the camera) and pybind11 (Debian's pybind11-dev), as
scripts/install_deps.sh installs them. UAVSIM_CMAKE_ARGS adds configure options; UAVSIM_BUILD_JOBS sets
the build's parallelism."""

import os
import shlex
import shutil
import subprocess
import sys

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)


class CMakeExtension(Extension):
    def __init__(self, name):
        super().__init__(name, sources=[])


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = os.path.abspath(os.path.join(self.build_temp, "cmake"))
        configure = [
            "cmake", "-S", REPO, "-B", build_dir, "-DCMAKE_BUILD_TYPE=Release",
            "-DUAVSIM_BUILD_SERVER=OFF", "-DUAVSIM_BUILD_TESTS=OFF", "-DUAVSIM_BUILD_BENCH=OFF",
            "-DUAVSIM_BUILD_VISION=OFF", f"-DPython3_EXECUTABLE={sys.executable}",
        ]
        if shutil.which("ninja"):
            configure += ["-G", "Ninja"]
        if shutil.which("ccache"):
            configure += ["-DCMAKE_CXX_COMPILER_LAUNCHER=ccache"]
        configure += shlex.split(os.environ.get("UAVSIM_CMAKE_ARGS", ""))
        jobs = os.environ.get("UAVSIM_BUILD_JOBS", str(os.cpu_count() or 1))
        subprocess.check_call(configure)
        subprocess.check_call(["cmake", "--build", build_dir, "--target", "uavsim_python_core", "-j", jobs])
        built = os.path.join(build_dir, "python", "uavsim")
        module = [f for f in os.listdir(built) if f.startswith("_core") and f.endswith(".so")]
        if len(module) != 1:
            raise RuntimeError(f"uavsim: the build made no single _core module in {built}: {module}")
        target = self.get_ext_fullpath(ext.name)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(os.path.join(built, module[0]), target)
        # OpenCV's codecs for JPEG camera frames, loaded by _core from its own folder when first needed
        codecs = os.path.join(built, "libuavsim_media_io.so")
        if os.path.exists(codecs):
            shutil.copyfile(codecs, os.path.join(os.path.dirname(target), "libuavsim_media_io.so"))


setup(ext_modules=[CMakeExtension("uavsim._core")], cmdclass={"build_ext": CMakeBuild})
