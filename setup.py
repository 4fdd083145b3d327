"""setuptools with a CMake extension: the build of the Python package geohaz (pyproject.toml says why).

The compiled module geohaz._geohaz is the CMake target geohaz_python (python/CMakeLists.txt); this
file only configures the project for the interpreter running it, builds that one target and copies
the module into the package. Environment:
  GEOHAZ_CMAKE_BUILD_DIR  the CMake build folder (default: setuptools' build_temp/cmake, under ./build)
  CMAKE_ARGS              extra configure options, e.g. "-DGEOHAZ_NATIVE=ON"
  CMAKE_BUILD_PARALLEL_LEVEL  build jobs (default 2)
  CMAKE_CXX_COMPILER_LAUNCHER=ccache  read by CMake itself at the first configure
"""
import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent


def project_version():
    """The version in CMakeLists.txt's project() call: one place for the apps, the libraries and this."""
    text = (ROOT / "CMakeLists.txt").read_text()
    m = re.search(r"project\(\s*geohaz\s+VERSION\s+([0-9][0-9.]*)", text)
    if not m:
        raise RuntimeError("no project(geohaz VERSION x.y.z) in CMakeLists.txt")
    return m.group(1)


class CMakeExtension(Extension):
    """A module built by the CMake target `target` (no sources of its own for setuptools)."""

    def __init__(self, name, target):
        super().__init__(name, sources=[])
        self.target = target


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build_dir = Path(os.environ.get("GEOHAZ_CMAKE_BUILD_DIR") or Path(self.build_temp) / "cmake").resolve()
        build_dir.mkdir(parents=True, exist_ok=True)
        configure = [
            "cmake", "-S", str(ROOT), "-B", str(build_dir),
            "-DCMAKE_BUILD_TYPE=Release",
            f"-DPython3_EXECUTABLE={sys.executable}",  # the interpreter the package is installed into
            "-DGEOHAZ_BUILD_PYTHON=ON", "-DGEOHAZ_BUILD_TESTS=OFF", "-DGEOHAZ_BUILD_BENCH=OFF",
            *shlex.split(os.environ.get("CMAKE_ARGS", "")),
        ]
        subprocess.run(configure, check=True)
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", "2")
        subprocess.run(["cmake", "--build", str(build_dir), "--target", ext.target, "-j", jobs], check=True)
        built = sorted((build_dir / "python" / "geohaz").glob("_geohaz*.so"))
        if not built:
            raise RuntimeError(f"the target {ext.target} built no _geohaz*.so in {build_dir}/python/geohaz")
        dest = Path(self.get_ext_fullpath(ext.name))
        dest.parent.mkdir(parents=True, exist_ok=True)
        # The newest one: a build folder reused by another interpreter keeps that one's module too.
        shutil.copyfile(max(built, key=lambda p: p.stat().st_mtime), dest)


setup(
    version=project_version(),
    ext_modules=[CMakeExtension("geohaz._geohaz", target="geohaz_python")],
    cmdclass={"build_ext": CMakeBuild},
)
