"""A contact point's reported state is what it did in the step (docs/design.md, "A point's
state"): slip where it slid in the step, stick where it did not, separated where its gap is open;
the result file, the contact CSV and the monitor say the same in every step."""
import re

import numpy as np
import pytest

from conftest import prep, result, solve
from mbcontact import meshgen
from mbcontact.results import output_times, read_contact, read_csv


def monitor_counts(stdout):
    """Per step, the (separated, stick, slip) of the monitor's last contact line of that step."""
    counts = {}
    for line in stdout.splitlines():
        m = re.match(r"step +(\d+) t .* contact: .* iterations \(merit .*separated (\d+), stick (\d+), slip (\d+)$", line)
        if m:
            counts[int(m.group(1))] = tuple(int(v) for v in m.groups()[1:])
    return counts


def steps_of(h5, stdout):
    """Per output step k >= 1: its time, each point's state and the slip it made in the step (the
    change of the file's accumulated slip, points matched by their master node), after checking
    that the file, the CSV and the monitor count the same states (a dynamic run's step 0, the
    initial state, has no contact solve and no monitor line)."""
    c = read_csv(result(h5, "_contact.csv"))
    mon = monitor_counts(stdout)
    out, before = [], None
    for k in range(len(output_times(result(h5, ".h5")))):
        q = read_contact(result(h5, ".h5"), step=k)
        state = q["state"]
        counts = tuple(int((state == s).sum()) for s in range(3))
        assert counts == (c["separated"][k], c["stick"][k], c["slip"][k]) == mon.get(k, counts) and (k == 0 or k in mon), (k, counts, mon.get(k))
        slip = {tuple(x): s for x, s in zip(q["reference"], q["slip"])}
        if before is not None:
            ds = np.array([np.linalg.norm(slip[x] - before.get(x, 0.0)) for x in slip])
            out.append((q["time"], state, ds))
        before = slip
    return out


@pytest.mark.parametrize("nproc", [1, 2])
def test_dragged_block_every_point_slips_in_gross_slip(tmp_path, nproc):
    """A block 1 x 1 x 0.3 (hex8, E = 20 GPa) pressed by p = 1 MPa on a base of tets (non-matching,
    mu = 0.6), dragged by its top at 0.3 m/s in dynamic steps of 0.02 s: 6 mm a step, against an
    elastic shear of mu p h / G = 2.2e-5 m, so from its second step on every point slides by about
    the drag (measured 5.8 to 6.4 mm a step; the five master nodes that leave the base are
    separated). Every point in contact is "slip" in every one of those steps. Before, the state was
    read from the step's mean traction, inside the cone by 1e-6 or not: the trapezoidal rule's
    period-2 oscillation put the mean force inside the cone every other step, and all 15 sliding
    points were "stick" there."""
    meshgen.boxes(str(tmp_path / "drag.msh"),
                  [dict(lo=(0, 0, 0), hi=(1, 1, 0.5), n=(3, 3, 1), name="base", cell="tet4"),
                   dict(lo=(0, 0, 0.5), hi=(1, 1, 0.8), n=(4, 4, 2), name="block", cell="hex8")])
    material = {"E": 2.0e10, "nu": 0.2, "density": 2500}
    scene = {"meshes": {"m": "drag.msh"},
             "bodies": {b: {"mesh": "m", "regions": b, "material": material} for b in ("base", "block")},
             "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": 0.6}],
             "dirichlet": [{"surface": "base_zmin", "components": "all"},
                           {"surface": "block_zmax", "components": ["x"], "value": 0.3, "time": {"table": [[0, 0], [1, 1]]}},
                           {"surface": "block_zmax", "components": ["y"]}],
             "loads": [{"kind": "pressure", "surface": "block_zmax", "value": 1.0e6, "time": "sudden"}],
             "analysis": {"type": "dynamic", "dt": 0.02, "final_time": 0.4}}
    h5 = prep(tmp_path, scene, name="drag")
    r = solve(h5, "-mbc_monitor", nproc=nproc)
    steps = steps_of(h5, r.stdout)
    assert len(steps) == 20
    for t, state, ds in steps[1:]:
        touching = state > 0
        assert touching.sum() >= 15 and np.all(ds[touching] > 0.5 * 6e-3), (t, ds)
        assert np.all(state[touching] == 2), (t, state)


@pytest.mark.parametrize("nproc", [1, 2])
def test_pad_against_soft_body_states_are_the_slip(tmp_path, nproc):
    """A pad-like soft body (1 x 1 x 0.5, E = 20 MPa) pressed by 0.1 MPa on a stiff base of tets
    (non-matching, mu = 0.3), its top dragged by 0.05 sin(pi t) m in dynamic steps of 0.02 s (at
    most U = 3.1 mm a step): it slides, stops while its top turns back through twice its elastic
    shear capacity mu p h / G = 2 mm (t = 0.5 to 0.6), then slides back, the contact search
    pairing its points anew as they pass the base's faces. In every step a point is "slip" where
    it slid (its slip in the step, from the file's slip, above 1e-12 U) and "stick" where it did
    not (below 1e-6 U: the sticking points move by 1e-16 to 1e-10 m), and in the steps of gross
    slip (the drag above 0.6 of its peak rate) all 25 points slip. The file, the CSV and the
    monitor agree in every step. Before, 34 of 100 steps disagreed: the CSV and the file counted
    up to 15 sliding points "stick" while the monitor said "stick 0" (the traction's test, made on
    the forces carried to the points the search after the step found)."""
    meshgen.boxes(str(tmp_path / "pad.msh"),
                  [dict(lo=(0, 0, 0), hi=(2, 1, 0.4), n=(5, 3, 1), name="base", cell="tet4"),
                   dict(lo=(0.5, 0, 0.4), hi=(1.5, 1, 0.9), n=(4, 4, 2), name="pad", cell="hex8")])
    t = np.linspace(0, 2, 81)
    scene = {"meshes": {"m": "pad.msh"},
             "bodies": {"base": {"mesh": "m", "regions": "base", "material": {"E": 2.0e10, "nu": 0.2, "density": 2500}},
                        "pad": {"mesh": "m", "regions": "pad", "material": {"E": 2.0e7, "nu": 0.3, "density": 1000, "damping": 5}}},
             "couples": [{"master": "pad_zmin", "slave": "base_zmax", "mu": 0.3}],
             "dirichlet": [{"surface": "base_zmin", "components": "all"},
                           {"surface": "pad_zmax", "components": ["x"], "value": 0.05,
                            "time": {"table": [[float(a), float(np.sin(np.pi * a))] for a in t]}},
                           {"surface": "pad_zmax", "components": ["y"]}],
             "loads": [{"kind": "pressure", "surface": "pad_zmax", "value": 1.0e5, "time": {"table": [[0, 0], [0.1, 1], [10, 1]]}}],
             "analysis": {"type": "dynamic", "dt": 0.02, "final_time": 2.0}}
    h5 = prep(tmp_path, scene, name="pad")
    r = solve(h5, "-mbc_monitor", nproc=nproc)
    assert r.stdout.count("rebuilt") > 10  # the search pairs the points anew
    U = 0.05 * np.pi * 0.02
    steps = steps_of(h5, r.stdout)
    assert len(steps) == 100
    seen = set()
    for t, state, ds in steps:
        assert np.all(ds[state == 2] > 1e-12 * U) and np.all(ds[state == 1] < 1e-6 * U), (t, state, ds)
        if abs(np.cos(np.pi * t)) > 0.6 and t > 0.1:
            assert np.all(state == 2), (t, state)
        seen.update(state)
    assert seen == {0, 1, 2}
