"""Shared helpers: write a scene from a dict, run mbcontact-prep and the solver."""
import os
import subprocess
import sys

import pytest
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "python"))
BUILD = os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build"))
SOLVER = os.path.join(BUILD, "mbcontact")
PREP = os.path.join(ROOT, "python", "mbcontact-prep")
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "PYTHONPATH": os.path.join(ROOT, "python")}


def load_script(relpath, name):
    """A script of the tree (e.g. meshes/hertz/build.py) as a module under a unique name: the
    scene scripts are all called build.py, and one sys.modules entry would serve them all."""
    import importlib.util
    path = os.path.join(ROOT, relpath)
    sys.path.insert(0, os.path.dirname(path))  # for the script's own sibling imports
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


def env():
    e = dict(os.environ)
    e.update(MPI_ENV)
    return e


def prep(tmp_path, scene, name="scene"):
    """Writes scene (a dict) as YAML beside its meshes and runs mbcontact-prep; returns the .h5 path."""
    yml = tmp_path / f"{name}.yaml"
    yml.write_text(yaml.safe_dump(scene, sort_keys=False))
    h5 = tmp_path / f"{name}.h5"
    r = subprocess.run([PREP, str(yml), "-o", str(h5)], capture_output=True, text=True, env=env())
    assert r.returncode == 0, r.stderr
    return h5


def info_to_files(options, prefix):
    """-info's messages into one file a rank (PETSc writes prefix.<rank>): on one stdout the
    ranks' lines interleave mid-line and a test's pattern can miss one."""
    options = list(options)
    if "-info" not in options:
        return options, False
    i = options.index("-info")
    spec = options[i + 1] if i + 1 < len(options) and not options[i + 1].startswith("-") else None
    options[i:i + (2 if spec is not None else 1)] = ["-info", prefix + (spec or "")]
    return options, True


def solve(h5, *options, nproc=1, check=True, timeout=600):
    """Runs the solver on nproc ranks; returns the CompletedProcess. On several ranks -info's
    messages follow the solver's own output rank by rank, each rank's lines whole."""
    import glob
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        prefix = os.path.join(tmp, "info")
        options, info = info_to_files(options, prefix) if nproc > 1 else (options, False)
        cmd = [SOLVER, *(["-scene", str(h5)] if str(h5) else []), *options]
        if nproc > 1:
            cmd = ["mpirun", "-n", str(nproc), *cmd]
        r = subprocess.run(cmd, capture_output=True, text=True, env=env(), timeout=timeout)
        if info:
            files = sorted(glob.glob(prefix + ".*"), key=lambda f: int(f.rsplit(".", 1)[1]))
            r.stdout += "".join(open(f).read() for f in files)
    if check:
        assert r.returncode == 0, f"{' '.join(cmd)}\n{r.stdout}\n{r.stderr}"
    return r


def result(h5, suffix):
    return str(h5)[:-3] + "_result" + suffix


@pytest.fixture
def run_dir(tmp_path):
    return tmp_path
