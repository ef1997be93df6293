"""Build hook of `pip install ./python` (pyproject.toml): put a libcupid.so inside the package.

Which library (the first that applies):
  - $CUPID_LIBRARY: that file, copied (an existing build, e.g. build/libcupid.so or a PETSc
    build's);
  - else libcupid built here with CMake from the repository this folder belongs to (its
    CMakeLists.txt one level up), Release, into python/build/cmake: the libcupid target only,
    with $CUPID_CMAKE_ARGS added to the configure line (e.g. "-DCUPID_WITH_PETSC=ON") and
    $CMAKE_BUILD_PARALLEL_LEVEL jobs (default: the CPUs).
The package loads its own copy first (cupid.library_path()), so `import cupid` works from any
folder without PYTHONPATH. A missing compiler, CMake or Debian package is a build error naming
the command that failed; scripts/install-deps.sh installs what the build needs.
"""
import os
import re
import shlex
import shutil
import subprocess

from setuptools import Distribution, setup
from setuptools.command.build_py import build_py

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def version():
    """The project's version from the top-level CMakeLists.txt (project(cupid VERSION x.y.z))."""
    try:
        text = open(os.path.join(ROOT, "CMakeLists.txt")).read()
    except OSError:
        return "0.0.0"
    m = re.search(r"project\(cupid VERSION ([0-9.]+)", text)
    return m.group(1) if m else "0.0.0"


def run(cmd):
    print("cupid: " + " ".join(shlex.quote(c) for c in cmd), flush=True)
    try:
        subprocess.run(cmd, check=True)
    except (OSError, subprocess.CalledProcessError) as e:
        raise SystemExit("cupid: building libcupid failed at `%s`: %s (scripts/install-deps.sh "
                         "installs the build's Debian packages; or set CUPID_LIBRARY to a built "
                         "libcupid.so)" % (" ".join(cmd), e))


def library():
    """The libcupid.so to bundle: $CUPID_LIBRARY, or one built with CMake."""
    given = os.environ.get("CUPID_LIBRARY")
    if given:
        if not os.path.isfile(given):
            raise SystemExit("cupid: CUPID_LIBRARY=%s is not a file" % given)
        return given
    if not os.path.isfile(os.path.join(ROOT, "CMakeLists.txt")):
        raise SystemExit("cupid: no CMakeLists.txt at %s to build libcupid from; set "
                         "CUPID_LIBRARY to a built libcupid.so" % ROOT)
    build = os.path.join(HERE, "build", "cmake")
    run(["cmake", "-S", ROOT, "-B", build, "-DCMAKE_BUILD_TYPE=Release", "-DCUPID_BUILD_TESTS=OFF"]
        + shlex.split(os.environ.get("CUPID_CMAKE_ARGS", "")))
    jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 1))
    run(["cmake", "--build", build, "--target", "cupid", "-j", jobs])
    return os.path.join(build, "libcupid.so")


class BuildWithLibrary(build_py):
    def run(self):
        super().run()
        target = os.path.join(self.build_lib, "cupid", "libcupid.so")
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copyfile(library(), target)  # the file itself, not a link into the build tree
        os.chmod(target, 0o755)


class BinaryDistribution(Distribution):
    """A wheel for this platform (the package holds a compiled library), not a pure one."""

    def has_ext_modules(self):
        return True


setup(version=version(), cmdclass={"build_py": BuildWithLibrary}, distclass=BinaryDistribution)
