"""The gravity dam scene (meshes/dam, docs/dam.md): the synthetic ground motion record, the
generated meshes, and small dams (3 monoliths, 3804 DOFs) solved statically and dynamically
against the dam's weight W, the hydrostatic thrust T and the sliding threshold mu = T / W."""
import re

import numpy as np
import pytest

from conftest import load_script, solve
from mbcontact.results import read_csv

dam = load_script("meshes/dam/build.py", "dam_build")
report = load_script("meshes/dam/report.py", "dam_report")
motion = load_script("meshes/dam/ground_motion.py", "dam_ground_motion")

SMALL = dict(h=15.0, monoliths=3)  # 3804 DOFs: monoliths 5 (6) x 1 x 7 (8) hex8 on a 9 x 13 x 5 foundation
# A static analysis solves only stick states here (docs/dam.md): water at 80 m and mu = 1 keep
# every base point inside its cone (T / W = 0.338, the heel stays compressed).
STATIC = dict(SMALL, level=80.0, mu_base=1.0, joints=False)


def test_ground_motion_record(tmp_path):
    """The shipped record is what ground_motion.py makes from its seed (to the 7 printed digits):
    peak 0.3 g, from rest (a = 0 at t = 0), ending near rest (|v| < 1 cm/s, |d| < 1 cm after the
    baseline correction), 20 s at 100 Hz."""
    t, a = motion.read(dam.RECORD)
    t2, a2 = motion.read(motion.write(str(tmp_path / "gm.csv")))
    assert np.array_equal(t, t2) and np.abs(a - a2).max() <= 1e-6 * np.abs(a).max()
    assert len(t) == 2001 and t[-1] == 20.0 and a[0] == 0.0
    assert abs(np.abs(a).max() / (0.3 * 9.81) - 1) < 1e-6
    v, d = motion.integrate(a, 0.01)
    assert abs(v[-1]) < 0.01 and abs(d[-1]) < 0.01 and np.abs(d).max() > 0.05  # a real record moves


@pytest.mark.parametrize("h", [25.0, 10.0])
def test_mesh(tmp_path, h):
    """The generated mesh: every hex positive, the monoliths' volume the section's times the
    width (each hex is a prism along y: shoelace area of its x-z face times its depth), the DOF
    count 3 x vertices, the joints' master nodes inside their slave faces, the foundation's
    contact surface covering the dam's footprint, and target_dofs within 10 %."""
    p = dam.Dam(h=h, monoliths=3).check()
    a = dam.layout(p)
    total = 0
    for k in range(1, 4):
        pts, cells, surf = dam.monolith(p, a, k)
        assert np.all(dam.min_corner_volume("hex8", pts, cells) > 0)
        x, z = pts[cells][:, [0, 1, 5, 4], 0], pts[cells][:, [0, 1, 5, 4], 2]
        area = 0.5 * np.abs(np.sum(x * np.roll(z, -1, axis=1) - np.roll(x, -1, axis=1) * z, axis=1))
        volume = np.sum(area * (pts[cells][:, 3, 1] - pts[cells][:, 0, 1]))
        assert abs(volume / (p.section_area() * p.width) - 1) < 1e-12
        total += len(pts)
        if k % 2:  # master joint faces: no node on the border of the joint's section
            nodes = pts[np.unique(surf[f"m{k}_ymax"])]
            xd = np.where(nodes[:, 2] <= p.z_knee, p.crest + p.slope * (p.z_knee - nodes[:, 2]), p.crest)
            assert np.all((nodes[:, 0] > 0) & (nodes[:, 0] < xd - 1e-9) & (nodes[:, 2] > 0) & (nodes[:, 2] < p.height))
    fpts, fcells, fsurf = dam.foundation(p, a)
    assert np.all(dam.min_corner_volume("hex8", fpts, fcells) > 0)
    contact = fpts[np.concatenate([fsurf["foundation_contact"], fsurf["heel_ring"]])]
    assert contact[:, :, 0].min() < 0 and contact[:, :, 0].max() > p.base
    assert contact[:, :, 1].min() < 0 and contact[:, :, 1].max() > 3 * p.width
    assert dam.count_dofs(p) == 3 * (total + len(fpts))
    for target in (5000, 50000):
        hh = dam.size_for_dofs(p, target)
        assert abs(dam.count_dofs(dam.replace(p, h=hh)) / target - 1) < 0.1


def test_short_foundation_has_no_floor_load(tmp_path):
    """A foundation that ends upstream within the contact ring (upstream 0.3 H) has no reservoir
    floor: the builder loads only the wet surfaces that have faces. Before, it loaded the empty
    'floor' and the scene's preparation stopped ("no such region"); the water still presses on
    the ring's upstream part (heel_ring)."""
    p, full = dam.Dam(**SMALL, upstream=0.3).check(), dam.Dam(**SMALL).check()
    assert dam.wet_surfaces(p, dam.layout(p)) == ["heel_ring"]
    assert dam.wet_surfaces(full, dam.layout(full)) == ["floor", "heel_ring"]
    h5 = dam.build(tmp_path, **STATIC, upstream=0.3)
    text = open(str(h5)[:-3] + ".yaml").read()
    assert "surface: heel_ring" in text and "surface: floor" not in text
    surfaces = dam.foundation(p, dam.layout(p))[2]
    assert len(surfaces["floor"]) == 0 and len(surfaces["heel_ring"]) > 0


def base_history(prefix):
    c = read_csv(prefix + "_contact.csv")
    return {k: v[c["couple"] == 1] for k, v in c.items()}


@pytest.mark.parametrize("nproc", [1, 2])
def test_static_resultants(tmp_path, nproc):
    """Self-weight and water, static, the monoliths held only by contact. The base resultant is
    the dam's weight and the water's thrust: W = rho g A_section width and T = gamma h^2 / 2 per
    width, both integrated exactly, so what is left is the equilibrium tolerance (out-of-balance
    force <= -mbc_static_rtol 1e-6 of the largest nodal force; observed 3e-8, asserted 1e-6).
    With mu W / T = 2.96 every point sticks and nothing slides: the largest slip is 1e-7 m
    (1e-4 of the crest's displacement) against the 0.1 m a slide would give. Two ranks give the
    same forces."""
    h5 = dam.build(tmp_path, **STATIC)
    r = solve(h5, nproc=nproc)
    prefix = str(h5)[:-3] + "_result"
    s = report.summarize(prefix)
    base = s["couples"][1]
    assert abs(base["vertical_over_weight"] - 1) < 1e-6 and abs(base["horizontal_over_thrust"] - 1) < 1e-6
    assert abs(base["force"][1]) < 1e-6 * s["weight"]
    assert base["slip_fraction"] == 0 and base["open_fraction"] == 0
    crest = abs(read_csv(prefix + "_points.csv")["crest_m2_ux"][-1])  # upstream: the weight leans it back
    assert crest > 1e-3 and base["max_sliding"] < 1e-4 * crest
    assert abs(base["safety_final"] / (1.0 * s["weight"] / s["thrust"]) - 1) < 1e-6
    assert abs(base["design_safety"] - s["weight"] / s["thrust"]) < 1e-12
    assert len(s["monoliths"]) == 3 and all(m["max_sliding"] < 1e-6 for m in s["monoliths"])
    assert "sliding factor of safety" in report.text(s), r.stdout


def test_static_sliding_fails(tmp_path):
    """mu = 0.2 < T / W = 0.338: no static equilibrium exists. The static analysis stops with
    one error line naming the step and saying so (a monolith's T / mu N = 1.69), within
    seconds, and writes no result beyond the start."""
    h5 = dam.build(tmp_path, **dict(STATIC, mu_base=0.2))
    r = solve(h5, check=False, timeout=120)
    assert r.returncode != 0
    lines = [l for l in r.stderr.splitlines() if l.strip()]
    assert len(lines) == 1 and "mbcontact: error:" in lines[0] and re.search(r"step 1\b", lines[0]), r.stderr
    assert "no static equilibrium" in lines[0] and "T / mu N" in lines[0], lines[0]


def test_dynamic_record_no_sliding(tmp_path):
    """Dynamic, with the joints: self-weight and water ramped over 0.5 s, held, then 0.5 s of the
    record's strong phase (from its 3rd second; PGA 0.3 g). Before the record the base carries W
    and T on average over the hold 0.5-1 s (measured +0.08 % and -0.05 %, hex8 and hex8i alike;
    asserted 0.5 %) under the ringing the ramp left (+-2.4 % in fz, +-2.2 % in fx; asserted 3 %):
    the value at t = 1 s alone, which this test used to assert within 0.5 %, is a sample of that
    ringing (hex8 -0.21 %, hex8i -0.63 % in fx); with mu W / T = 2.96, more than the
    record's 0.3 g adds (T / W + 0.3 < mu), the base does not slide: the computed mu N / |F_t|
    stays above 2 and a few heel points slip for a step or two in the strongest cycles (0.2 mm,
    asserted < 1 mm, against half a metre in the sliding case below); the joints open by 0.5 mm
    and slide by 1 mm (asserted 1 and 2 mm). The record shakes the crest relative to the base several times more than the
    ringing did."""
    h5 = dam.build(tmp_path, "dynamic", dt=0.02, ramp=0.5, eq_start=1.0, eq_duration=0.5, record_from=3.0,
                   **dict(SMALL, level=80.0, mu_base=1.0, mu_joint=1.0))
    solve(h5)
    prefix = str(h5)[:-3] + "_result"
    s = report.summarize(prefix)
    b = base_history(prefix)
    hold = (b["t"] >= 0.5 - 1e-9) & (b["t"] <= 1.0 + 1e-9)
    fz, fx = b["fz"][hold] / s["weight"] - 1, -b["fx"][hold] / s["thrust"] - 1
    assert abs(fz.mean()) < 5e-3 and abs(fx.mean()) < 5e-3, (fz.mean(), fx.mean())
    assert np.abs(fz).max() < 3e-2 and np.abs(fx).max() < 3e-2, (np.abs(fz).max(), np.abs(fx).max())
    assert s["couples"][1]["max_sliding"] < 1e-3 and s["couples"][1]["safety_min"] > 1.5
    joints = [c for k, c in s["couples"].items() if k > 1]
    assert len(joints) == 2 and all(c["max_opening"] < 1e-3 and c["max_sliding"] < 2e-3 for c in joints)
    p = read_csv(prefix + "_points.csv")
    drift = p["crest_m2_ux"] - p["heel_m2_ux"]
    quiet, shaken = np.ptp(drift[(p["t"] > 0.8) & (p["t"] <= 1.0)]), np.ptp(drift[p["t"] > 1.0])
    assert shaken > 3 * quiet, (quiet, shaken)


def test_dynamic_sliding_matches_block(tmp_path):
    """mu = 0.2 < T / W: loaded by the ramp (0.5 s, self-weight and water together), the dam slides
    downstream. The base's slip at t = 1 s is a rigid block's under the net force (T - mu W) f(t)
    and the mass-proportional Rayleigh damping alpha M v (which drags a sliding body too):
    x'' + alpha x' = (T / W - mu) g f(t), within 3 % (observed 0.8 %); the slide, half a metre,
    dwarfs the elastic displacements."""
    h5 = dam.build(tmp_path, "dynamic", dt=0.02, ramp=0.5, eq_start=1.0, eq_duration=0.0, **dict(SMALL, mu_base=0.2))
    solve(h5)
    prefix = str(h5)[:-3] + "_result"
    s = report.summarize(prefix)
    p = dam.Dam(**dict(SMALL, mu_base=0.2))
    alpha, _ = dam.rayleigh(p)
    a0 = (p.thrust() / p.weight() - 0.2) * 9.81
    x = v = 0.0
    dt = 1e-4
    for t in np.arange(0, 1.0, dt):  # semi-implicit Euler, fine enough at 1e-4 s
        v += (a0 * min((t + dt / 2) / 0.5, 1) - alpha * v) * dt
        x += v * dt
    slide = s["couples"][1]["max_sliding"]
    assert abs(slide / x - 1) < 0.03, (slide, x)
    assert s["couples"][1]["design_safety"] < 1


@pytest.mark.parametrize("nproc", [1, 2])
def test_static_builder_defaults_with_joints(tmp_path, nproc):
    """The builder's own static dam (water at 0.95 H, mu 0.8, contraction joints), default
    options: every monolith is held only by contact, so each is a free body with its six rigid
    modes in the multiplier problem (no spring). Converges with base resultants W and T to 1e-6
    (the equilibrium tolerance), the joints carrying self-balanced forces; partial slip and heel
    opening are allowed. This failed before the Newton solve and the exact free bodies."""
    h5 = dam.build(tmp_path, **dict(SMALL, joints=True))
    solve(h5, nproc=nproc)
    s = report.summarize(str(h5)[:-3] + "_result")
    base = s["couples"][1]
    assert abs(base["vertical_over_weight"] - 1) < 1e-6 and abs(base["horizontal_over_thrust"] - 1) < 1e-6
    assert abs(base["force"][1]) < 1e-6 * s["weight"]


def test_joints_on_a_mesh_too_coarse_for_them_are_refused(tmp_path):
    """At 2e3 DOFs the odd monoliths have 2 x 3 elements on a joint, all on its upstream, downstream
    or crest edge, so the joint's master surface was empty and the prep stopped on a missing
    region m1_ymax; the builder now says why, and 3e3 DOFs builds."""
    with pytest.raises(ValueError, match=r"too coarse for joints: monolith m1 .* take a smaller h"):
        dam.build(tmp_path / "a", target_dofs=2e3, joints=True)
    assert str(dam.build(tmp_path / "b", target_dofs=3e3, joints=True)).endswith(".h5")
