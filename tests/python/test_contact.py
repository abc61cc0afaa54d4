"""Contact forces in the Newmark step: the paper's two-block example."""

import numpy as np
import pytest

from conftest import load_script, prep, solve
import yaml
from mbcontact.results import read_csv

blocks = load_script("meshes/blocks/build.py", "blocks_build")


@pytest.mark.parametrize("dt,newmark,final_time", [(0.01, (0.25, 0.5), 2.5), (0.04, (0.3025, 0.6), 4.0),
                                                    (0.06, (0.3025, 0.6), 4.0), (0.10, (0.3025, 0.6), 4.0)])
def test_two_blocks_steady_state(tmp_path, dt, newmark, final_time):
    """Block 2 (100 N/m3 applied suddenly) on block 1, mu = 0.6, damping 200, at the paper's four
    steps: once settled (the last 0.5 s) the top of block 2 stays at -1.5e-4 m and the contact face
    at -1.0e-4 m within 0.1 % (exact: block 1 carries 1e4 Pa over 100 m, block 2 its own weight),
    every contact point sticking. At dt = 0.01 s the paper's trapezoidal rule settles; at the larger
    steps the stiff modes the step cannot resolve ring on under it (C = 200 M hardly damps them:
    up to 31 % at dt = 0.1 s after 2 s), so those runs use the dissipative Newmark beta = 0.3025,
    gamma = 0.6. Histories (the paper's figures 7 and 8) go to CSV and PNG."""
    h5 = blocks.build(tmp_path, dt=dt, final_time=final_time)
    r = solve(h5, "-mbc_monitor", "-mbc_newmark_beta", str(newmark[0]), "-mbc_newmark_gamma", str(newmark[1]))
    p = read_csv(str(h5)[:-3] + "_result_points.csv")
    late = p["t"] >= final_time - 0.5 - 1e-9
    assert late.sum() >= 5
    assert np.abs(p["top_uz"][late] / -1.5e-4 - 1).max() < 1e-3
    assert np.abs(p["face_uz"][late] / -1.0e-4 - 1).max() < 1e-3
    # the blocks stay put sideways (no lateral load), and the contact points stick
    assert np.abs(p["top_ux"]).max() < 1e-3 * 1.5e-4 and np.abs(p["face_uy"]).max() < 1e-3 * 1.5e-4
    last = [l for l in r.stdout.splitlines() if "contact: " in l and " in " in l and "iterations (merit" in l][-1]
    assert "separated 0" in last and "slip 0" in last and "stick 441" in last
    assert r.stdout.count("flexibility matrix rebuilt") == 1  # D built once: the pairs do not change
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(p["t"], p["top_uz"], label="top of block 2 (fig. 7)")
    ax.plot(p["t"], p["face_uz"], label="contact face (fig. 8)")
    ax.axhline(-1.5e-4, color="k", lw=0.5)
    ax.axhline(-1.0e-4, color="k", lw=0.5)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("u_z [m]")
    ax.set_title(f"two blocks, dt = {dt} s")
    ax.legend()
    fig.savefig(tmp_path / "blocks_histories.png", dpi=80)
    assert (tmp_path / "blocks_histories.png").stat().st_size > 1000


def test_prescribed_dofs_on_the_contact_surface(tmp_path):
    """Block 1's top face, the slave surface of the couple, is prescribed in all components (a
    rigid foundation): their rows of H are zero, D comes from block 2 alone and stays regular.
    Block 2 settles on it: contact face at 0, top at -rho g L^2 / (2E) = -5e-5 m (0.1 %)."""
    h5 = blocks.build(tmp_path, dt=0.04, final_time=4.0)
    with open(tmp_path / "blocks.yaml") as f:
        scene = yaml.safe_load(f)
    scene["dirichlet"] = [{"surface": "block1_zmin", "components": "all"}, {"surface": "block1_zmax", "components": "all"}]
    h5 = prep(tmp_path, scene, name="fixed")
    r = solve(h5, "-mbc_monitor", "-mbc_newmark_beta", "0.3025", "-mbc_newmark_gamma", "0.6")
    p = read_csv(str(h5)[:-3] + "_result_points.csv")
    late = p["t"] >= 3.5 - 1e-9
    assert np.abs(p["top_uz"][late] / -5e-5 - 1).max() < 1e-3
    assert np.abs(p["face_uz"][late]).max() < 1e-3 * 5e-5
    last = [l for l in r.stdout.splitlines() if "contact: " in l and " in " in l and "iterations (merit" in l][-1]
    assert "CONVERGED" in last and "stick 441" in last
