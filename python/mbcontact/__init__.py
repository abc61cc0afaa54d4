"""mbcontact: the multibody contact solver from Python.

Scene preparation (mbcontact.prep, mbcontact-prep), result files (mbcontact.results) and, once
the project is built, the petsc4py binding (mbcontact.Scene, mbcontact.Solver: docs/python.md).
The compiled parts (_core, _version) live in the build tree (build/python/mbcontact) or, after
`pip install .`, beside this file: __path__ spans both."""
import os as _os
import pkgutil as _pkgutil

__path__ = _pkgutil.extend_path(__path__, __name__)


def _source_version():
    """project(VERSION) of the CMakeLists.txt beside this source tree (used before a build)."""
    import re
    cmake = _os.path.join(_os.path.dirname(_os.path.dirname(_os.path.dirname(_os.path.abspath(__file__)))), "CMakeLists.txt")
    with open(cmake) as f:
        return re.search(r"project\(mbcontact VERSION ([0-9.]+)", f.read()).group(1)


try:
    from ._version import __version__
except ImportError:
    __version__ = _source_version()

_BINDING = ("Scene", "Solver", "Body", "Error")


def __getattr__(name):
    # The binding loads PETSc: only on first use, so that mbcontact-prep does not need it.
    if name in _BINDING:
        try:
            from . import _core
        except ImportError as e:
            raise ImportError(f"mbcontact.{name} needs the compiled binding mbcontact._core ({e}): "
                              "build the project (make build) and put build/python on PYTHONPATH, "
                              "or pip install .") from e
        return getattr(_core, name)
    raise AttributeError(f"module 'mbcontact' has no attribute {name!r}")
