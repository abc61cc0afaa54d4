"""Uplift on a couple's faces (docs/scene.md, Couples, `uplift`; docs/dam.md, Uplift): a 4 x 2 m
block on a base, the joint z = 0 from the heel x = 0 to the toe x = 4.

- The law with a drain line: heads H1 = 10 m, H2 = 2 m, drains at X = 1 m of efficiency 0.5:
  H3 = H2 + (1 - E)(H1 - H2)(L - X)/L = 5 m; int h ds = 18 m^2 and int h s ds = 27.333 m^3, so
  U = gamma b 18 = 353 160 N at x = 1.5185 m, up on the block (master), down on the base (slave).
- A block on a base under that uplift: the contact's normal resultant is W - U (equilibrium of
  the block held only by contact, to the static tolerance).
- A block pushed over by the water on its upstream face, the heel opening: with `penetration`
  the reservoir's pressure gamma (level - z) fills the open part from the heel, the law starts at
  the crack's tip; repeated load steps at the same load converge to the cracked state, whose
  uplift is gamma b (H1 w + H1 (L - w) / 2) with w the wet length.
"""
import re

import numpy as np
import pytest

from conftest import prep, result, solve
from mbcontact import meshgen
from mbcontact.results import read_contact, read_csv

GAMMA = 9810.0
B = 2.0  # the joint's width along y
L = 4.0


def resultants(stdout):
    """{load index: (kind, F (3,), M (3,))} from the -mbc_view lines."""
    out = {}
    for m in re.finditer(r"load (\d+) \((\w+)\): resultant (\S+) (\S+) (\S+), moment about the origin (\S+) (\S+) (\S+)", stdout):
        v = np.array([float(x) for x in m.groups()[2:]])
        out.setdefault(int(m.group(1)), []).append((m.group(2), v[:3], v[3:]))
    return out


def block_scene(tmp_path, uplift, height=4.0, loads=(), mu=0.8, steps=1, density=2400.0):
    """The block (8 x 2 x 4 elements: a node on the drain line x = 1) on a base of other
    elements (6 x 3 x 1: the drain line and the crack's tip cross its faces)."""
    meshgen.boxes(str(tmp_path / "m.msh"), [
        dict(lo=(0, 0, 0), hi=(L, B, height), n=(8, 2, 4), name="block"),
        dict(lo=(-0.5, -0.25, -1), hi=(L + 0.5, B + 0.25, 0), n=(6, 3, 1), name="base")])
    return {"meshes": {"m": "m.msh"},
            "bodies": {"block": {"mesh": "m", "regions": "block", "material": {"E": 2.5e10, "nu": 0.2, "density": density}},
                       "base": {"mesh": "m", "regions": "base", "material": {"E": 2.0e10, "nu": 0.25}}},
            "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": mu, "uplift": uplift}],
            "dirichlet": [{"surface": "base_zmin"}],
            "loads": [{"kind": "gravity", "vector": [0, 0, -9.81], "bodies": "block"}, *loads],
            "analysis": {"type": "static", "dt": 1.0, "final_time": float(steps)}}


DRAINED = {"origin": [0, 0, 0], "direction": [1, 0, 0], "length": L, "heel_head": 10.0, "tail_head": 2.0,
           "drain": 1.0, "drain_efficiency": 0.5, "unit_weight": GAMMA}
U_DRAINED = GAMMA * B * 18.0
X_DRAINED = 27.0 + 1.0 / 3.0  # int h s ds
X_DRAINED /= 18.0


@pytest.mark.parametrize("nproc", [1, 2])
def test_drained_law_resultant_and_point_of_action(tmp_path, nproc):
    """The assembled nodal loads (-mbc_view) and the contact CSV's uplift against the law's
    integral: on the block (a node on the drain line: exact, 1e-12), on the base (the drain line
    crosses its faces: 12 x 12 sub-cells, measured 2e-6, asserted 1e-4), equal and opposite."""
    h5 = prep(tmp_path, block_scene(tmp_path, DRAINED))
    r = solve(h5, "-mbc_view", nproc=nproc)
    loads = [v for k in sorted(resultants(r.stdout)) for v in resultants(r.stdout)[k] if v[0] == "uplift"]
    assert len(loads) == 2
    (_, Fm, Mm), (_, Fs, Ms) = loads  # block (master), base (slave)
    assert np.allclose(Fm, [0, 0, U_DRAINED], rtol=0, atol=1e-12 * U_DRAINED)
    # moment about the origin of (0, 0, U) at (x, 1, 0): (U y, -U x, 0)
    assert np.allclose(Mm, [U_DRAINED * 1.0, -U_DRAINED * X_DRAINED, 0], rtol=0, atol=1e-11 * U_DRAINED)
    assert np.allclose(Fs, -Fm, rtol=0, atol=1e-11 * U_DRAINED)
    assert np.allclose(Ms, -Mm, rtol=0, atol=1e-11 * U_DRAINED)
    c = read_csv(result(h5, "_contact.csv"))
    assert abs(c["uplift"][-1] - U_DRAINED) < 1e-12 * U_DRAINED
    assert abs(c["uplift_x"][-1] - X_DRAINED) < 1e-12 and abs(c["uplift_y"][-1] - 1.0) < 1e-12
    assert abs(c["uplift_z"][-1]) < 1e-12 and c["wet_length"][-1] == 0


@pytest.mark.parametrize("nproc", [1, 2])
def test_block_normal_resultant_is_weight_minus_uplift(tmp_path, nproc):
    """The block (W = 2400 g 32 = 753 408 N) under the drained law: N = W - U to the static
    tolerance (1e-6 asserted, with the block held by contact alone), no tangential force."""
    h5 = prep(tmp_path, block_scene(tmp_path, DRAINED))
    solve(h5, nproc=nproc)
    c = read_csv(result(h5, "_contact.csv"))
    W = 2400 * 9.81 * L * B * 4.0
    assert abs(c["fz"][-1] - (W - U_DRAINED)) < 1e-6 * W
    assert abs(c["normal_force"][-1] - (W - U_DRAINED)) < 1e-6 * W
    assert abs(c["fx"][-1]) < 1e-6 * W and abs(c["fy"][-1]) < 1e-6 * W
    assert c["separated"][-1] == 0


LEVEL = 5.0  # the reservoir against the block's upstream face, and its head at the heel


@pytest.mark.parametrize("nproc", [1, 2])
def test_open_joint_takes_the_reservoir_pressure(tmp_path, nproc):
    """The water on the upstream face (5 m, the block 4 m high) tilts the block about its toe:
    the heel opens. With penetration the open part from the heel carries gamma (level - z) =
    gamma 5 on both faces, the law (no drains: H1 -> 0) from the tip on. Load steps at the same
    load iterate the wet length to the cracked state: the last two steps agree; the points before
    the wet length are open, the one at it closed; the uplift is the law's integral with that
    wet length (the master's kink at a node: 1e-10)."""
    up = {"origin": [0, 0, 0], "direction": [1, 0, 0], "length": L, "tail_head": 0.0, "penetration": True}
    water = {"kind": "hydrostatic", "surface": "block_xmin", "level": LEVEL, "unit_weight": GAMMA}
    h5 = prep(tmp_path, block_scene(tmp_path, up, loads=[water], steps=8))
    solve(h5, nproc=nproc)
    c = read_csv(result(h5, "_contact.csv"))
    w = c["wet_length"]
    assert w[-1] > 0 and w[-1] == w[-2], w
    U = GAMMA * B * (LEVEL * w[-1] + LEVEL * (L - w[-1]) / 2)
    assert abs(c["uplift"][-1] - U) < 1e-10 * U
    pts = read_contact(str(result(h5, ".h5")), step=-1)
    x, p = pts["reference"][:, 0], pts["pressure"]
    assert np.all(p[x < w[-1] - 1e-9] <= 0)
    assert np.any(p[np.abs(x - w[-1]) < 1e-9] > 0)  # the front stops at the first closed point
    # the block's equilibrium: vertical W - U, horizontal the water's thrust on its face
    W = 2400 * 9.81 * L * B * 4.0
    T = GAMMA * B * (LEVEL * 4.0 - 8.0)
    assert abs(c["fz"][-1] - (W - U)) < 1e-6 * W and abs(c["fx"][-1] + T) < 1e-6 * W


def prep_error(tmp_path, scene):
    """mbcontact-prep on a scene that must be refused: exit status non-zero, one message."""
    import subprocess

    import yaml

    from conftest import PREP, env
    yml = tmp_path / "bad.yaml"
    yml.write_text(yaml.safe_dump(scene, sort_keys=False))
    r = subprocess.run([PREP, str(yml), "-o", str(tmp_path / "bad.h5")], capture_output=True, text=True, env=env())
    assert r.returncode != 0, r.stdout
    assert "Traceback" not in r.stderr, r.stderr
    return r.stderr


@pytest.mark.parametrize("change, words", [
    (dict(drain=5.0), ["couples[0].uplift (couple k=1).drain", "within the joint"]),
    (dict(drain_efficiency=1.5), ["drain_efficiency", "[0, 1]"]),
    (dict(drain_efficiency=None), ["drain_efficiency", "required with a drain line"]),
    (dict(direction=[0, 0, 1]), ["direction", "not along the joint"]),
    (dict(direction=[0, 0, 0]), ["direction", "must not be zero"]),
    (dict(length=0), ["length", "must be > 0"]),
    (dict(tail_head=12.0), ["tail_head", "above heel_head"]),
    (dict(table=[[0, 1e5], [4, 2e4]]), ["heel_head", "a table gives the pressure by itself"]),
    (dict(unit_weight=None), ["unit_weight", "required", "no hydrostatic load"]),
    (dict(heel_head=None), ["level", "required", "no hydrostatic load"]),
    (dict(penetration=True), ["level", "required", "no hydrostatic load"]),
    (dict(drain={"point": [1, 0, 0], "normal": [0, 1, 0]}), ["drain.normal", "must cross the joint's direction"]),
    (dict(drain={"point": [-1, 0, 0], "normal": [1, 0, 0]}), ["drain", "not downstream"]),
    (dict(colour="blue"), ["couples[0].uplift (couple k=1)", "colour"]),
    (dict(origin=None), ["couples[0].uplift (couple k=1)", "origin"]),
])
def test_input_errors(tmp_path, change, words):
    up = dict(DRAINED)
    for key, value in change.items():
        if value is None:
            up.pop(key, None)
        else:
            up[key] = value
    err = prep_error(tmp_path, block_scene(tmp_path, up))
    for w in words:
        assert w in err, (w, err)


def test_table_and_levels_from_the_hydrostatic_load(tmp_path):
    """A table p(s) (the drained law's pressures at its kinks: the same resultant), a law whose
    level, unit weight and heel head come from the scene's hydrostatic load (heel head = level -
    the heel's height), and the same with the drain line given as a (slanted) plane."""
    table = {"origin": [0, 0, 0], "direction": [2, 0, 0], "length": L,
             "table": [[0, GAMMA * 10], [1, GAMMA * 5], [4, GAMMA * 2]]}
    water = {"kind": "hydrostatic", "surface": "base_xmin", "level": 10.0, "unit_weight": GAMMA}  # on the fixed base
    law = {"origin": [0, 0, 0], "direction": [1, 0, 0], "length": L, "tail_head": 2.0, "drain": 1.0,
           "drain_efficiency": 0.5}
    plane = dict(law, drain={"point": [1.0, 5.0, -3.0], "normal": [2.0, 0.0, 0.5]})  # a slanted curtain through x = 1 at z = 0
    plane["drain"]["point"] = [1.0 - 0.25 * -3.0, 5.0, -3.0]  # (point - origin) . n / (n . d) = 1
    for up in (table, law, plane):
        h5 = prep(tmp_path, block_scene(tmp_path, up, loads=[water]))
        r = solve(h5, "-mbc_view")
        F = [v for k in sorted(resultants(r.stdout)) for v in resultants(r.stdout)[k] if v[0] == "uplift"][0][1]
        assert abs(F[2] - U_DRAINED) < 1e-12 * U_DRAINED, (up, F)


@pytest.mark.parametrize("nproc", [1, 2])
def test_dam_with_lift_joints_and_uplift(tmp_path, nproc):
    """meshes/dam/build.py with two lift joints and the uplift (2 monoliths, h = 14 m: 4 296 DOFs),
    static, 12 load steps (the water raised over 6): the base's uplift is the drained law's integral (heel 95 m, drains at
    5 % of B = 78 m with E = 0.5, no tail water: H3 = 0.5 95 (B - X) / B), the base's contact
    normal force W - U, each lift joint's uplift its own law's, and report.py prints the sliding
    factor of safety per joint plane, FS = mu N' / T (no cohesion here), and the cracked length."""
    import subprocess

    from conftest import ROOT, env, load_script
    dam = load_script("meshes/dam/build.py", "dam_build_uplift")
    h5 = dam.build(tmp_path, h=14.0, monoliths=2, lift_joints=(30.0, 60.0), uplift=True)
    p = dam.Dam(h=14.0, monoliths=2, lift_joints=(30.0, 60.0), uplift=True).check()
    solve(h5, nproc=nproc)
    prefix = str(h5)[:-3] + "_result"
    c = read_csv(prefix + "_contact.csv")
    width = 2 * p.width
    for k, z in ((1, 0.0), (3, 30.0), (4, 60.0)):
        L, H1 = p.section_width(z), p.water - z
        X = 0.05 * L
        H3 = 0.5 * H1 * (L - X) / L
        U = GAMMA * width * ((H1 + H3) / 2 * X + H3 / 2 * (L - X))
        row = c["couple"] == k
        assert abs(c["uplift"][row][-1] / U - 1) < 1e-12, (k, c["uplift"][row][-1], U)
    base = c["couple"] == 1
    W = 2 * p.weight()
    assert abs(c["normal_force"][base][-1] - (W - c["uplift"][base][-1])) < 1e-6 * W
    r = subprocess.run(["/usr/bin/python3", f"{ROOT}/meshes/dam/report.py", prefix], capture_output=True, text=True,
                       env=env(), timeout=120)
    assert r.returncode == 0, r.stderr
    assert "joint plane" in r.stdout and "lift 2 (z = 60)" in r.stdout, r.stdout
    report = load_script("meshes/dam/report.py", "dam_report_uplift")
    s = report.summarize(prefix)
    for k in (1, 3, 4):
        q = s["planes"][k]
        h = {name: col[c["couple"] == k] for name, col in c.items()}
        fs = 0.8 * h["normal_force"][-1] / np.hypot(h["fx"][-1], h["fy"][-1])
        assert abs(q["fs_final"] / fs - 1) < 1e-12 and q["cohesion"] == 0
        assert 0 <= q["cracked_length"][-1] <= q["length"]


def classical_cracked_base(B, height, h, rho=2400.0, g=9.81):
    """USACE EM 1110-2-2200 / FERC chapter III's cracked-base iteration for a rectangular block of
    base B and height `height` (per unit width), the reservoir h deep against it, no tail water,
    no drains: with a crack T from the heel, the uplift is the reservoir's head h over the crack
    and linear from h to 0 over the rest; the effective base pressure is linear over B - T, zero at
    the tip, so its resultant lies (B - T) / 3 from the toe: B - T = 3 e, e = M_toe / (W - U)."""
    W, Hf, zH = rho * g * B * height, GAMMA * h * h / 2, h / 3
    T = 0.0
    for _ in range(1000):
        U = GAMMA * h * T + GAMMA * h * (B - T) / 2
        MU = GAMMA * h * T * (B - T / 2) + GAMMA * h * (B - T) / 2 * (2 / 3) * (B - T)
        e = (W * B / 2 - Hf * zH - MU) / (W - U)
        Tn = max(0.0, B - 3 * e)
        if abs(Tn - T) < 1e-12 * B:
            break
        T = Tn
    return T


def test_cracked_base_against_the_classical_iteration(tmp_path):
    """A 10 m wide, 15 m high block, rigid in effect (E = 1e13), on a thin soft bed (0.1 m, E = 1e9,
    nu = 0: a Winkler bed: the linear base pressure over a rigid base the classical analysis
    assumes), the reservoir 15 m deep on its upstream face, uplift h at the heel to 0 at the toe,
    the water entering the crack: 30 load steps at the same load iterate the wet length as the
    classical computation iterates the crack (3 steps here, 15 there). Classical T = 3.036 m;
    computed 3.000 m (points 0.125 m apart; the zero of the pressure line through the first closed
    points 2.92 m), asserted within 2 % of B. A flexible block departs from the linear pressure:
    E = 1e11 on 0.5 m gives 2.875 m (zero of the pressure line 2.70 m)."""
    B, Hb, h = 10.0, 15.0, 15.0
    meshgen.boxes(str(tmp_path / "m.msh"), [
        dict(lo=(0, 0, 0), hi=(B, 1, Hb), n=(80, 1, 6), name="block"),
        dict(lo=(-0.25, 0, -0.1), hi=(B + 0.25, 1, 0), n=(85, 1, 1), name="bed")])
    scene = {"meshes": {"m": "m.msh"},
             "bodies": {"block": {"mesh": "m", "regions": "block", "material": {"E": 1e13, "nu": 0.0, "density": 2400.0}},
                        "bed": {"mesh": "m", "regions": "bed", "material": {"E": 1e9, "nu": 0.0}}},
             "couples": [{"master": "block_zmin", "slave": "bed_zmax", "mu": 1.0,
                          "uplift": {"origin": [0, 0, 0], "direction": [1, 0, 0], "length": B, "tail_head": 0.0,
                                     "penetration": True}}],
             "dirichlet": [{"surface": "bed_zmin"}],
             "loads": [{"kind": "gravity", "vector": [0, 0, -9.81], "bodies": "block"},
                       {"kind": "hydrostatic", "surface": "block_xmin", "level": h, "unit_weight": GAMMA}],
             "analysis": {"type": "static", "dt": 1.0, "final_time": 30.0}}
    h5 = prep(tmp_path, scene)
    solve(h5)
    c = read_csv(result(h5, "_contact.csv"))
    T = classical_cracked_base(B, Hb, h)
    w = c["wet_length"]
    print(f"classical crack {T:.4f} m, computed wet length {w[-1]:.4f} m; wet lengths {w}")
    assert abs(T - 3.0357) < 1e-3
    assert w[-1] == w[-2] and abs(w[-1] - T) <= 0.02 * B


def test_dynamic_ramp_follows_the_time_table(tmp_path):
    """Dynamic, the weight, the water and the uplift ramped together over 0.2 s and held: the
    uplift in the CSV is the law's resultant times the ramp's factor at every step, and with
    penetration the wet length follows the heel's opening step by step; at the end the block has
    settled (N + U = W within 1 %: what is left of the ringing)."""
    ramp = {"table": [[0, 0], [0.2, 1]]}
    up = {"origin": [0, 0, 0], "direction": [1, 0, 0], "length": L, "tail_head": 0.0, "penetration": True, "time": ramp}
    water = {"kind": "hydrostatic", "surface": "block_xmin", "level": LEVEL, "unit_weight": GAMMA, "time": ramp}
    scene = block_scene(tmp_path, up, loads=[water])
    scene["loads"][0]["time"] = ramp
    scene["bodies"]["base"]["material"]["density"] = 2700.0
    scene["analysis"] = {"type": "dynamic", "dt": 0.01, "final_time": 0.6, "newmark": {"beta": 0.3025, "gamma": 0.6}}
    h5 = prep(tmp_path, scene)
    solve(h5)
    c = read_csv(result(h5, "_contact.csv"))
    w, f = c["wet_length"], np.minimum(c["t"] / 0.2, 1.0)
    U = f * GAMMA * B * (LEVEL * w + LEVEL * (L - w) / 2)
    assert np.allclose(c["uplift"], U, rtol=1e-10, atol=0)
    assert w.max() > 0
    W = 2400 * 9.81 * L * B * 4.0
    assert abs(c["fz"][-1] + c["uplift"][-1] - W) < 0.01 * W


@pytest.mark.parametrize("nproc", [1, 2])
def test_each_master_body_has_its_own_wet_front(tmp_path, nproc):
    """Two blocks side by side across the direction (two monoliths) on one base, one couple: the
    water pushes on block a only, whose heel opens; block b stays closed. The wet front is the
    master body's: a's zone carries gamma 5 over its wet length, b's the dry law, so the uplift is
    gamma b (H1 w + H1 (L - w) / 2) + gamma b H1 L / 2 (1e-10), with w the CSV's (the largest)."""
    meshgen.boxes(str(tmp_path / "m.msh"), [
        dict(lo=(0, 0, 0), hi=(L, B, 4.0), n=(8, 2, 4), name="a"),
        dict(lo=(0, B, 0), hi=(L, 2 * B, 4.0), n=(8, 2, 4), name="b"),
        dict(lo=(-0.5, -0.25, -1), hi=(L + 0.5, 2 * B + 0.25, 0), n=(6, 5, 1), name="base")])
    concrete = {"E": 2.5e10, "nu": 0.2, "density": 2400.0}
    scene = {"meshes": {"m": "m.msh"},
             "bodies": {"a": {"mesh": "m", "regions": "a", "material": concrete},
                        "b": {"mesh": "m", "regions": "b", "material": concrete},
                        "base": {"mesh": "m", "regions": "base", "material": {"E": 2.0e10, "nu": 0.25}}},
             "couples": [{"master": ["a_zmin", "b_zmin"], "slave": "base_zmax", "mu": 0.8,
                          "uplift": {"origin": [0, 0, 0], "direction": [1, 0, 0], "length": L, "tail_head": 0.0,
                                     "penetration": True}}],
             "dirichlet": [{"surface": "base_zmin"}],
             "loads": [{"kind": "gravity", "vector": [0, 0, -9.81], "bodies": ["a", "b"]},
                       {"kind": "hydrostatic", "surface": "a_xmin", "level": LEVEL, "unit_weight": GAMMA}],
             "analysis": {"type": "static", "dt": 1.0, "final_time": 6.0}}
    h5 = prep(tmp_path, scene)
    solve(h5, nproc=nproc)
    c = read_csv(result(h5, "_contact.csv"))
    w = c["wet_length"][-1]
    assert w > 0 and c["wet_length"][-2] == w
    U = GAMMA * B * (LEVEL * w + LEVEL * (L - w) / 2) + GAMMA * B * LEVEL * L / 2
    assert abs(c["uplift"][-1] - U) < 1e-10 * U
    pts = read_contact(str(result(h5, ".h5")), step=-1)
    y, p = pts["reference"][:, 1], pts["pressure"]
    assert np.all(p[y > B + 1e-9] > 0)  # b closed everywhere


def test_restart_keeps_the_water_in_the_joint(tmp_path):
    """A checkpoint inside the tilted block's load steps, its heel open and wet: the checkpoint
    holds the wet length the next step takes (the points it comes from are not written), so the
    restart ends bitwise where the uninterrupted run ends (a restart that starts dry takes another
    path to the cracked state)."""
    up = {"origin": [0, 0, 0], "direction": [1, 0, 0], "length": L, "tail_head": 0.0, "penetration": True}
    water = {"kind": "hydrostatic", "surface": "block_xmin", "level": LEVEL, "unit_weight": GAMMA}
    h5 = prep(tmp_path, block_scene(tmp_path, up, loads=[water], steps=5))
    solve(h5, "-mbc_output", str(tmp_path / "full"))
    part = str(tmp_path / "part")
    solve(h5, "-mbc_output", part, "-mbc_checkpoint_every", "2", "-mbc_final_time", "2")
    r = solve(h5, "-mbc_output", part, "-mbc_restart", part + "_checkpoint.h5", "-mbc_monitor")
    assert "restarted from" in r.stdout
    a, b = read_csv(str(tmp_path / "full_contact.csv")), read_csv(part + "_restart_contact.csv")
    assert a["wet_length"][2] > 0, a["wet_length"]  # the water in the joint when the checkpoint was taken
    n = len(b["t"])
    assert n == 3 and np.array_equal(a["t"][-n:], b["t"]), (a["t"], b["t"])
    for key in ("wet_length", "uplift", "fx", "fz"):  # every step after the checkpoint
        assert np.array_equal(a[key][-n:], b[key]), (key, a[key], b[key])
