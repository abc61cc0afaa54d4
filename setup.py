"""Builds the compiled half of the Python package with the project's CMake (pyproject.toml):
libmbcontact, the Cython extension mbcontact._core and _version.py, installed into the package
by `cmake --install --component python` (the extension finds the library beside it)."""
import os
import re
import subprocess

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = os.path.dirname(os.path.abspath(__file__))


def version():
    with open(os.path.join(ROOT, "CMakeLists.txt")) as f:
        return re.search(r"project\(mbcontact VERSION ([0-9.]+)", f.read()).group(1)


class CMakeBuild(build_ext):
    def build_extension(self, ext):
        build = os.path.abspath(os.path.join(self.build_temp, "cmake"))
        out = os.path.abspath(self.build_lib)
        subprocess.run(["cmake", "-S", ROOT, "-B", build, "-DCMAKE_BUILD_TYPE=RelWithDebInfo", "-DMBC_PYTHON=ON"], check=True)
        subprocess.run(["cmake", "--build", build, "--target", "mbcontact_core", "-j", str(os.cpu_count() or 1)], check=True)
        subprocess.run(["cmake", "--install", build, "--component", "python", "--prefix", out], check=True)


# setuptools would build in build/, the project's CMake build folder: keep to a corner of it
setup(version=version(), ext_modules=[Extension("mbcontact._core", sources=[])], cmdclass={"build_ext": CMakeBuild},
      options={"build": {"build_base": "build/pip"}})
