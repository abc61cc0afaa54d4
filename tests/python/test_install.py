"""cmake --install into a temporary prefix, then a user's C program (tests/install/driver.c)
built against the installed tree, once with pkg-config and once with find_package(mbcontact),
solves a column under self-weight: the top's u_z is -rho g L^2 / (2E) exactly (hex8 layered
in z, nu = 0: 1D superconvergence, see test_body.py), so 1e-10 relative is rounding only."""
import os
import re
import shutil
import subprocess

import pytest

from conftest import BUILD, ROOT, env, prep
from mbcontact import meshgen, __version__

E, RHO, G, L = 30e9, 2500.0, 9.81, 10.0


def cmake_version():
    with open(os.path.join(ROOT, "CMakeLists.txt")) as f:
        return re.search(r"project\(mbcontact VERSION ([0-9.]+)", f.read()).group(1)


@pytest.fixture(scope="module")
def prefix(tmp_path_factory):
    p = tmp_path_factory.mktemp("prefix")
    r = subprocess.run(["cmake", "--install", BUILD, "--prefix", str(p)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return p


@pytest.fixture(scope="module")
def column(tmp_path_factory):
    d = tmp_path_factory.mktemp("column")
    meshgen.box(d / "col.msh", (0, 0, 0), (1, 1, L), n=(1, 1, 10), cell="hex8", volume_name="col")
    return prep(d, {"meshes": {"m": "col.msh"},
                    "bodies": {"col": {"mesh": "m", "regions": ["col"], "material": {"E": E, "nu": 0.0, "density": RHO}}},
                    "dirichlet": [{"surface": "zmin", "components": "all"}],
                    "loads": [{"kind": "gravity", "vector": [0, 0, -G]}],
                    "analysis": {"type": "static"}})


def check_driver(exe, scene, *options):
    r = subprocess.run([str(exe), "-scene", str(scene), "-mbc_output", str(scene)[:-3] + "_drv", *options],
                       capture_output=True, text=True, env=env(), timeout=120)
    assert r.returncode == 0, r.stdout + r.stderr
    assert f"mbcontact {cmake_version()}" in r.stdout
    umin = float(re.search(r"body col min u (\S+)", r.stdout).group(1))
    exact = -RHO * G * L**2 / (2 * E)
    assert abs(umin - exact) < 1e-10 * abs(exact), (umin, exact)
    return r.stdout


def test_installed_tree(prefix):
    for f in ["include/mbcontact.h", "include/mbcversion.h", "include/mbc/private/solverimpl.h",
              "lib/pkgconfig/mbcontact.pc", "lib/cmake/mbcontact/mbcontactConfig.cmake",
              "lib/cmake/mbcontact/mbcontactConfigVersion.cmake", "bin/mbcontact"]:
        assert (prefix / f).exists(), f
    assert any(n.startswith("libmbcontact.so") for n in os.listdir(prefix / "lib"))
    # the installed executable finds the installed library (RPATH $ORIGIN/../lib)
    r = subprocess.run([str(prefix / "bin" / "mbcontact")], capture_output=True, text=True, env=env())
    assert r.returncode == 1 and "No scene file" in r.stderr, r.stderr


def test_one_version():
    """project(VERSION) is the one number: the header, pkg-config, the Python package."""
    v = cmake_version()
    assert __version__ == v
    with open(os.path.join(BUILD, "include", "mbcversion.h")) as f:
        assert f'#define MBC_VERSION_STRING   "{v}"' in f.read()
    with open(os.path.join(BUILD, "mbcontact.pc")) as f:
        assert f"Version: {v}" in f.read()


def test_pkg_config_driver(prefix, column, tmp_path):
    e = env()
    e["PKG_CONFIG_PATH"] = str(prefix / "lib" / "pkgconfig")
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "mbcontact"], capture_output=True, text=True, env=e)
    assert flags.returncode == 0, flags.stderr
    exe = tmp_path / "driver"
    cc = subprocess.run(["cc", os.path.join(ROOT, "tests", "install", "driver.c"), "-o", str(exe), *flags.stdout.split()],
                        capture_output=True, text=True)
    assert cc.returncode == 0, cc.stderr
    out = check_driver(exe, column, "-mbc_solver_view", "-mbc_scene_view")
    assert "MBCSolver Object: 1 MPI process" in out and "body col: ranks 0-0, 132 DOFs, 12 prescribed" in out, out  # 2 x 2 x 11 vertices, 4 fixed
    assert out.count("Scene ") == 2, out  # -mbc_scene_view at load, and inside the solver's view


def test_cmake_package_driver(prefix, column, tmp_path):
    src = tmp_path / "src"
    shutil.copytree(os.path.join(ROOT, "tests", "install"), src)
    for cmd in (["cmake", "-S", str(src), "-B", str(tmp_path / "b"), f"-DCMAKE_PREFIX_PATH={prefix}"],
                ["cmake", "--build", str(tmp_path / "b")]):
        r = subprocess.run(cmd, capture_output=True, text=True)
        assert r.returncode == 0, r.stdout + r.stderr
    check_driver(tmp_path / "b" / "driver", column)


def test_pip_install_into_a_venv(tmp_path):
    """pip install . (no build isolation: the build needs only what make installs) into a venv
    made with --system-site-packages (petsc4py, numpy, h5py from Debian): from another folder,
    without PYTHONPATH, `import mbcontact` is the venv's copy with the compiled binding, and the
    mbcontact-prep console script runs."""
    venv = tmp_path / "venv"
    subprocess.run(["/usr/bin/python3", "-m", "venv", "--system-site-packages", str(venv)], check=True, timeout=120)
    r = subprocess.run([str(venv / "bin" / "pip"), "install", "-q", "--no-build-isolation", ROOT],
                       capture_output=True, text=True, timeout=900)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    e = {k: v for k, v in env().items() if k != "PYTHONPATH"}
    r = subprocess.run([str(venv / "bin" / "python"), "-c", "import mbcontact, mbcontact._core; print(mbcontact.__file__, mbcontact.__version__)"],
                       capture_output=True, text=True, env=e, cwd=tmp_path, timeout=120)
    assert r.returncode == 0, r.stderr
    path, version = r.stdout.split()
    assert path.startswith(str(venv)) and version == cmake_version(), r.stdout
    r = subprocess.run([str(venv / "bin" / "mbcontact-prep"), "--help"], capture_output=True, text=True, env=e, timeout=120)
    assert r.returncode == 0 and "usage" in r.stdout.lower(), r.stdout + r.stderr
