"""Rigid bodies (six DOFs seen through their nodes) against a very stiff body and a closed form:
a block pressed on a rigid base (the rigid body as the slave side) gives the stiff base's answer,
a rigid mass started at 1 m/s against an elastic bar (the rigid body as the master side) slows as
v0 exp(-rho c A t / m) until the bar's reflection returns, and a rigid body's bad inputs are
refused. Small meshes: a second or two each."""
import numpy as np
import pytest

from conftest import prep, result, solve
from mbcontact import meshgen
from mbcontact.results import point_history, read_csv


def block_on_base(tmp_path, rigid, name):
    meshgen.boxes(str(tmp_path / "m.msh"), [dict(lo=(-0.5, -0.5, -1), hi=(1.5, 1.5, 0), n=(2, 2, 1), name="base"),
                                            dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(3, 3, 3), name="block")])
    base = {"mesh": "m", "regions": "base", "rigid": True} if rigid else \
        {"mesh": "m", "regions": "base", "material": {"E": 1.0e16, "nu": 0.3}}
    return prep(tmp_path, {
        "meshes": {"m": "m.msh"},
        "bodies": {"base": base, "block": {"mesh": "m", "regions": "block", "material": {"E": 1.0e6, "nu": 0.3}}},
        "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": 0.5}],
        "dirichlet": [{"body": "base"} if rigid else {"surface": "base_zmin"}],
        "loads": [{"kind": "pressure", "surface": "block_zmax", "value": 1.0e3}],
        "analysis": {"type": "static"},
        "output": {"points": {"top": {"x": [0.5, 0.5, 1], "body": "block"}, "corner": {"x": [1, 1, 1], "body": "block"}}},
    }, name=name)


@pytest.mark.parametrize("nproc", [1, 2])
def test_rigid_base_is_a_stiff_base(tmp_path, nproc):
    """A block (E 1e6, nu 0.3, friction 0.5) pressed by 1 kPa onto a base held rigid (`rigid:
    true`, its motion prescribed by `dirichlet: {body: base}`) or made of E = 1e16 and held at its
    bottom: the block's points move the same to 1e-8 (the stiff base's own compliance is 1e-10 of
    the block's) and the base carries the 1 kN load in both."""
    runs = {}
    for rigid in (True, False):
        h5 = block_on_base(tmp_path, rigid, "rigid" if rigid else "stiff")
        solve(h5, nproc=nproc)
        runs[rigid] = (read_csv(result(h5, "_points.csv")), read_csv(result(h5, "_contact.csv")))
    (p, c), (q, d) = runs[True], runs[False]
    for key in ("top_uz", "corner_ux", "corner_uy", "corner_uz"):
        assert abs(p[key][-1] - q[key][-1]) < 1e-8 * abs(q["top_uz"][-1]), key
    assert abs(q["top_uz"][-1]) > 5e-4  # the block's own squeeze, ~ p H / E
    assert abs(c["normal_force"][-1] / 1e3 - 1) < 1e-8 and abs(d["normal_force"][-1] / 1e3 - 1) < 1e-6


@pytest.mark.parametrize("mass", ["density", "given"])
def test_rigid_mass_on_a_bar(tmp_path, mass):
    """A rigid cube of mass m = 0.01 kg (density 10, or `mass: 0.01` with the reference point off
    the cube's centre; free along x only: the other five components
    prescribed at 0) starts at v0 = 1 m/s (`initial`) against a free elastic bar (E = rho = 1,
    A = 0.01 m2, 1 m, c = 1 m/s, impedance Z = rho c A = 0.01 kg/s). Until the wave reflected at
    the bar's far end returns (t = 2 L / c = 2 s) the bar is semi-infinite for the mass: v(t) =
    v0 exp(-Z t / m) = exp(-t). Generalized-alpha at c dt / dx = 1/2: within 2 % of v0 over the
    first steps (the discrete impact's start: 1.3 % measured) and 1 % from 0.2 s to 1.5 s
    (measured 0.3 %; the wave front's dispersion grows after that)."""
    meshgen.boxes(str(tmp_path / "m.msh"), [dict(lo=(-0.1, 0, 0), hi=(0, 0.1, 0.1), n=(1, 1, 1), name="mass"),
                                            dict(lo=(0, 0, 0), hi=(1, 0.1, 0.1), n=(20, 1, 1), name="bar")])
    h5 = prep(tmp_path, {
        "meshes": {"m": "m.msh"},
        "bodies": {"mass": {"mesh": "m", "regions": "mass", **({"rigid": True, "material": {"density": 10.0}} if mass == "density"
                            else {"rigid": {"mass": 0.01, "reference": [-0.1, 0, 0]}})},
                   "bar": {"mesh": "m", "regions": "bar", "material": {"E": 1.0, "nu": 0.0, "density": 1.0}}},
        "couples": [{"master": "mass_xmax", "slave": "bar_xmin"}],
        "dirichlet": [{"body": "mass", "components": ["y", "z", "rx", "ry", "rz"]}, {"body": "bar", "components": ["y", "z"]}],
        "initial": [{"body": "mass", "velocity": [1.0, 0, 0]}],
        "analysis": {"type": "dynamic", "dt": 0.025, "final_time": 1.5, "scheme": "generalized_alpha"},
        "output": {"every": 1000000, "fields": ["displacement"], "points": {"m": {"x": [-0.1, 0, 0], "body": "mass"}}},
    })
    solve(h5)
    h = point_history(result(h5, "_points.csv"), "m")
    error = np.abs(h["abs_v"][:, 0] - np.exp(-h["t"]))
    assert error.max() < 0.02 and error[h["t"] >= 0.2].max() < 0.01
    assert np.abs(h["abs_v"][:, 1:]).max() < 1e-12  # prescribed


def test_rigid_inputs_refused(tmp_path):
    """A rigid body's inertia that is not symmetric positive definite or comes without its mass, a material with more than a
    density, rotation components on a deformable body, and a spring on a rigid body: each refused,
    naming the key."""
    import subprocess
    import yaml
    from conftest import PREP, env
    meshgen.boxes(str(tmp_path / "m.msh"), [dict(lo=(0, 0, -1), hi=(1, 1, 0), n=(1, 1, 1), name="base"),
                                            dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(1, 1, 1), name="block")])
    good = {"meshes": {"m": "m.msh"},
            "bodies": {"base": {"mesh": "m", "regions": "base", "rigid": True},
                       "block": {"mesh": "m", "regions": "block", "material": {"E": 1.0e6}}},
            "couples": [{"master": "block_zmin", "slave": "base_zmax"}],
            "dirichlet": [{"body": "base"}, {"surface": "block_zmax", "components": ["x", "y"]}],
            "analysis": {"type": "static"}}
    cases = [
        (("bodies", "base", "rigid"), {"inertia": [[1, 0, 0], [0, -1, 0], [0, 0, 1]]}, "bodies.base.rigid.inertia"),
        (("bodies", "base", "rigid"), {"inertia": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}, "bodies.base.rigid.inertia: give the mass"),
        (("bodies", "base", "material"), {"density": 1.0, "E": 3.0}, "bodies.base.material.E"),
        (("dirichlet",), [{"body": "block", "components": ["rx"]}], "dirichlet[0].components"),
        (("springs",), [{"nodes": "base_zmin", "stiffness": [1, 1, 1]}], "springs[0].nodes"),
    ]
    for path, value, message in cases:
        scene = yaml.safe_load(yaml.safe_dump(good))
        target = scene
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value
        yml = tmp_path / "bad.yaml"
        yml.write_text(yaml.safe_dump(scene))
        r = subprocess.run([PREP, str(yml), "-o", str(tmp_path / "bad.h5")], capture_output=True, text=True, env=env())
        assert r.returncode != 0 and message in r.stderr and "Traceback" not in r.stderr, (message, r.stderr)
