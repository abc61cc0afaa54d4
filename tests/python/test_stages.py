"""Staged analysis (a static stage, then a dynamic one from its state) and checkpoint/restart:
a restarted run repeats the uninterrupted one (1 and 2 ranks, and on another rank count), also
after SIGTERM; a block under self-weight stays at rest through a dynamic stage without ground
motion; the staged dam balances W and T in its static stage; bad input is named."""
import math
import signal
import subprocess
import time

import h5py
import numpy as np
import pytest

from conftest import SOLVER, env, load_script, prep, result, solve
from mbcontact import meshgen
from mbcontact.results import read_body, read_contact, read_csv

G = 9.81


def incline(tmp_path, final_time=0.06):
    """The sliding incline of test_contact_dynamics (30 degrees, mu 0.3: every point slips)."""
    meshgen.boxes(str(tmp_path / "incline.msh"),
                  [dict(lo=(-0.5, -0.5, -1.0), hi=(2.5, 1.5, 0.0), n=(3, 2, 2), name="base"),
                   dict(lo=(0, 0, 0), hi=(1, 1, 0.5), n=(4, 4, 2), name="block")])
    th = math.radians(30)
    return prep(tmp_path, {
        "meshes": {"m": "incline.msh"},
        "bodies": {"base": {"mesh": "m", "regions": "base", "material": {"E": 1e9, "nu": 0.25, "density": 2000}},
                   "block": {"mesh": "m", "regions": "block",
                             "material": {"E": 1e9, "nu": 0.25, "density": 2000, "rayleigh_beta": 8e-4}}},
        "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": 0.3}],
        "dirichlet": [{"surface": "base_zmin", "components": "all"}, {"surface": "base_zmax", "components": "all"}],
        "loads": [{"kind": "gravity", "vector": [G * math.sin(th), 0, -G * math.cos(th)], "time": "sudden",
                   "bodies": ["block"]}],
        "analysis": {"type": "dynamic", "dt": 1e-3, "final_time": final_time},
        "output": {"every": 10, "fields": ["displacement"], "energy": True},
    }, name="incline")


def final_state(h5file):
    u = read_body(h5file, "block", step=-1)
    c = read_contact(h5file, step=-1)
    return u["time"], u["displacement"], c["force"]


def assert_same(a, b, rtol=1e-12):
    ta, ua, fa = final_state(a)
    tb, ub, fb = final_state(b)
    assert ta == tb
    assert np.abs(ua - ub).max() <= rtol * np.abs(ua).max()
    assert np.abs(fa - fb).max() <= rtol * np.abs(fa).max()
    assert np.abs(ua).max() > 1e-3 and (read_contact(a, step=-1)["state"] == 2).all()  # it slides


@pytest.mark.parametrize("save, load", [(1, 1), (2, 2), (2, 1)])
def test_restart_equals_uninterrupted(tmp_path, save, load):
    """Checkpoint at step 25 of 60 of the sliding block, restart (on `load` ranks), compare the last
    step with the run that was not interrupted: displacements and contact forces to 1e-12
    (measured: bitwise equal)."""
    h5 = incline(tmp_path)
    solve(h5, "-mbc_output", str(tmp_path / "full"), nproc=save)
    part = str(tmp_path / "part")
    solve(h5, "-mbc_output", part, "-mbc_checkpoint_every", "25", "-mbc_final_time", "0.03", nproc=save)
    with h5py.File(part + "_checkpoint.h5") as f:
        assert f["state"][0] == 25 and f["bodies/block/u"].shape == (75 * 3,)
    r = solve(h5, "-mbc_output", part, "-mbc_restart", part + "_checkpoint.h5", "-mbc_monitor", nproc=load)
    assert "restarted from" in r.stdout
    assert_same(str(tmp_path / "full.h5"), part + "_restart.h5")
    assert read_csv(part + "_restart_energy.csv")["t"][0] == pytest.approx(0.026)


def test_sigterm_leaves_a_checkpoint(tmp_path):
    """SIGTERM mid-run: the run stops after a step, writes its checkpoint and says how to go on;
    the restart ends where the uninterrupted run does, with the same answer."""
    h5 = incline(tmp_path, final_time=0.3)
    solve(h5, "-mbc_output", str(tmp_path / "full"))
    prefix = str(tmp_path / "k")
    p = subprocess.Popen([SOLVER, "-scene", str(h5), "-mbc_output", prefix, "-mbc_monitor"], env=env(),
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    for line in p.stdout:  # a few steps done
        if line.startswith("step    20 ") and "max|u|" in line:
            break
    p.send_signal(signal.SIGTERM)
    out, err = p.communicate(timeout=60)
    assert p.returncode == 128 + signal.SIGTERM and "-mbc_restart" in err, err
    solve(h5, "-mbc_output", prefix, "-mbc_restart", prefix + "_checkpoint.h5")
    assert_same(str(tmp_path / "full.h5"), prefix + "_restart.h5")


def block_on_base(tmp_path, stages, name="staged"):
    meshgen.boxes(str(tmp_path / "b.msh"), [dict(lo=(-0.5, -0.5, -1.0), hi=(1.5, 1.5, 0.0), n=(2, 2, 2), name="base"),
                                            dict(lo=(0, 0, 0), hi=(1, 1, 0.5), n=(3, 3, 2), name="block")])
    return prep(tmp_path, {
        "meshes": {"m": "b.msh"},
        "bodies": {"base": {"mesh": "m", "regions": "base", "material": {"E": 1e9, "nu": 0.25, "density": 2000}},
                   "block": {"mesh": "m", "regions": "block", "material": {"E": 1e9, "nu": 0.25, "density": 2000}}},
        "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": 0.6}],
        "dirichlet": [{"surface": "base_zmin", "components": "all"}],
        "loads": [{"kind": "gravity", "vector": [0, 0, -G]}],
        "stages": stages,
        "output": {"every": 5, "fields": ["displacement"]},
    }, name=name)


ZERO_MOTION = [{"name": "gravity", "analysis": {"type": "static"}},
               {"name": "quake", "analysis": {"type": "dynamic", "dt": 1e-3, "final_time": 1.02},
                "loads": [{"kind": "gravity", "vector": [-1, 0, 0], "time": {"table": [[0, 0], [10, 0]]}}]}]


def test_dynamic_stage_without_ground_motion_stays_at_rest(tmp_path):
    """A block held only by contact on a fixed base: static self-weight to t = 1, then 20 dynamic
    steps with a zero ground motion. The dynamic stage starts from the static state with v = 0
    and the acceleration equilibrium gives (0): displacements stay within 1e-10, velocities ~0,
    the contact resultant stays the weight. The result file holds both stages' outputs in
    order, /stage says which; -log_view has a stage per analysis stage."""
    h5 = block_on_base(tmp_path, ZERO_MOTION)
    r = solve(h5, "-mbc_static_rtol", "1e-12", "-mbc_multiplier_rtol", "1e-14", "-log_view")
    assert "MBC stage 0 gravity" in r.stdout and "MBC stage 1 quake" in r.stdout
    out = result(h5, ".h5")
    with h5py.File(out) as f:
        times, stage = f["time"][:], f["stage"][:]
    assert list(stage) == [0, 1, 1, 1, 1, 1] and times[0] == 1.0 and times[-1] == pytest.approx(1.02)
    u0 = read_body(out, "block", step=0)["displacement"]
    for k in range(1, len(times)):
        u = read_body(out, "block", step=k)["displacement"]
        assert np.abs(u - u0).max() < 1e-10 * np.abs(u0).max()
    c = read_csv(result(h5, "_contact.csv"))
    weight = 2000 * 0.5 * G
    assert np.allclose(c["fz"], weight, rtol=1e-9) and np.abs(c["fx"]).max() < 1e-9 * weight
    with open(result(h5, "_reactions.csv")) as f:
        rows = [line.split(",") for line in f.read().split()]
    fz = float(rows[-1][rows[0].index("fz")])  # the base's support carries the block too
    assert abs(fz / (weight + 2000 * 2 * 2 * 1 * G) - 1) < 1e-9


dam = load_script("meshes/dam/build.py", "dam_build_stages")


def test_staged_dam(tmp_path):
    """The dam builder's staged scene (smallest size): the static stage's base resultant balances
    the weight W and the water thrust T (1e-6, the equilibrium tolerance), then the first dynamic
    steps of the record run from that state, the base still carrying W."""
    h5 = dam.build(tmp_path, "staged", dt=0.02, eq_duration=0.06, record_from=3.0, h=15.0, monoliths=3,
                   level=80.0, mu_base=1.0, joints=False)
    solve(h5)
    c = read_csv(result(h5, "_contact.csv"))
    base = {k: v[c["couple"] == 1] for k, v in c.items()}
    w, t = 3 * dam.build.info["weight"], 3 * dam.build.info["thrust"]  # per monolith
    assert base["t"][0] == 1.0 and len(base["t"]) == 4
    assert abs(base["fz"][0] / w - 1) < 1e-6 and abs(-base["fx"][0] / t - 1) < 1e-6
    assert abs(base["fz"][-1] / w - 1) < 0.05
    with h5py.File(result(h5, ".h5")) as f:
        assert list(f["stage"][:]) == [0, 1]


@pytest.mark.parametrize("stages, message", [
    ([{"analysis": {"type": "static"}, "lodas": []}], "stages[0].lodas: unknown key"),
    ([{"name": "s", "analysis": {"dt": 1}}], "stages[0].analysis: missing required key 'type'"),
    ([{"analysis": {"type": "static", "final_time": 2}}, {"analysis": {"type": "static", "final_time": 1}}],
     "stages[1].analysis.final_time: must be > 2"),
])
def test_bad_stage(tmp_path, stages, message):
    meshgen.boxes(str(tmp_path / "b.msh"), [dict(lo=(0, 0, 0), hi=(1, 1, 1), n=(1, 1, 1), name="b")])
    yml = tmp_path / "bad.yaml"
    import yaml
    yml.write_text(yaml.safe_dump({"meshes": {"m": "b.msh"}, "bodies": {"b": {"mesh": "m", "regions": "b", "material": {"E": 1}}},
                                   "dirichlet": [{"surface": "b_zmin"}], "stages": stages}))
    from conftest import PREP
    r = subprocess.run([PREP, str(yml), "--check"], capture_output=True, text=True, env=env())
    assert r.returncode == 1 and message in r.stderr, r.stderr


def test_restart_from_another_scene(tmp_path):
    """A checkpoint of the incline given to the staged block: refused, naming both scenes."""
    h5 = incline(tmp_path, final_time=0.002)
    solve(h5, "-mbc_output", str(tmp_path / "i"), "-mbc_checkpoint_every", "1")
    other = block_on_base(tmp_path, ZERO_MOTION)
    r = solve(other, "-mbc_restart", str(tmp_path / "i_checkpoint.h5"), check=False)
    assert r.returncode != 0 and "written for another scene" in r.stderr and "i_checkpoint.h5" in r.stderr, r.stderr
    r = solve(other, "-mbc_restart", str(h5), check=False)
    assert r.returncode != 0 and "is not an mbcontact checkpoint" in r.stderr, r.stderr
