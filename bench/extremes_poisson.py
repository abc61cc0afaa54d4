#!/usr/bin/python3
"""Numerical stability on extreme cases (issue 17): Poisson's ratio 0 ... 0.499 and volumetric locking.

Two contact scenes, each swept over nu = 0, 0.3, 0.45, 0.49, 0.499 and the elements hex8, hex8i,
hex8b (B-bar) and tet4:
  confined  a block [0,1]^2 x [1,1.5] (4 x 4 x 1 cells) pressed by p on its top onto a base [0,1]^3
            (2 x 2 x 2 cells), frictionless; the base's bottom fixed, its x and y faces on
            frictionless walls (u_x = 0, u_y = 0): the base is in uniaxial strain, the block
            (held only by contact) in uniaxial stress. Reference, exact for every element (linear
            fields): top u_z = -p (L / M + L / (2 E)) with the oedometric modulus
            M = E (1 - nu) / ((1 + nu) (1 - 2 nu)), 167 E at nu = 0.499. Checks the conditioning
            (lambda / mu = 499 at nu = 0.499), not locking.
  lame      two concentric quarter tubes, 1 <= r <= 1.5 and 1.5 <= r <= 2, in frictionless
            contact at r = 1.5 (matching vertices), plane strain (u_z = 0 on both ends), symmetry
            planes x = 0 and y = 0, pressure p inside. The stress is radial-symmetric, so the
            frictionless interface transmits it as a welded one: the reference is Lame's single
            thick cylinder 1 <= r <= 2, u_r(1) = (1 + nu) p a^2 / (E (b^2 - a^2)) ((1 - 2 nu) a +
            b^2 / a) (a = 1, b = 2). Near nu = 1/2 the field tends to the isochoric u = B / r,
            which full-integration hex8 and tet4 cannot follow (volumetric locking). Error: the
            mean radial displacement of the inner surface's vertices against Lame; the modelling
            error (faceted circles, 12 cells per quarter, 3 through each wall) is that of hex8b at
            nu = 0: see docs/stability.md.
Columns: the multiplier solves' converged reasons, their iterations, the static iterations, the
error, wall time; pass: every multiplier solve CONVERGED and error < 1e-8 (confined), < LAME_TOL
(lame). A locking element fails the lame case near nu = 1/2: listed as "locking (use hex8b)".

  bench/extremes_poisson.py [--smoke] [--plot PNG]

Other benches import cases(work, smoke) (a list of dicts, one per case).
"""
import argparse
import os
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "python"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import monitor  # noqa: E402  (bench/monitor.py)
from mbcontact import meshgen  # noqa: E402
from mbcontact.prep import prepare  # noqa: E402
from mbcontact.results import read_body, read_csv  # noqa: E402

NUS = (0.0, 0.3, 0.45, 0.49, 0.499)
ELEMENTS = ("hex8", "hex8i", "hex8b", "tet4")
E, P = 2.0e10, 1.0e6
EXACT_TOL = 1e-8  # confined: exact fields, only rounding and the multiplier tolerance remain
LAME_TOL = 0.0075  # lame: about 2x hex8b's worst error over the sweep (0.34 %, the mesh's); docs/stability.md
RA, RB, RC, LZ = 1.0, 1.5, 2.0, 0.25  # inner, contact and outer radii; axial length
N_LAME = (3, 12, 1)  # cells per tube: radial, per quarter, axial


def options(element):
    return () if element == "tet4" else ("-body_element", element)


def confined(work, name, element, nu, L=1.0):
    """The block on the laterally confined base; returns (computed top u_z, exact, monitor, wall)."""
    cell = "tet4" if element == "tet4" else "hex8"
    meshgen.boxes(os.path.join(work, f"{name}.msh"),
                  [dict(lo=(0, 0, 0), hi=(L, L, L), n=(2, 2, 2), name="base", cell=cell),
                   dict(lo=(0, 0, L), hi=(L, L, 1.5 * L), n=(4, 4, 1), name="block", cell=cell)])
    mat = {"E": E, "nu": nu}
    scene = {"meshes": {"m": f"{name}.msh"},
             "bodies": {"base": {"mesh": "m", "regions": "base", "material": mat},
                        "block": {"mesh": "m", "regions": "block", "material": mat}},
             "couples": [{"master": "block_zmin", "slave": "base_zmax", "mu": 0.0}],
             "dirichlet": [{"surface": "base_zmin", "components": ["z"]}]
             + [{"surface": f"{b}_{s}", "components": [s[0]]} for b in ("base", "block") for s in ("xmin", "xmax", "ymin", "ymax")],
             "loads": [{"kind": "pressure", "surface": "block_zmax", "value": P}],
             "analysis": {"type": "static"},
             "output": {"points": {"top": {"x": [L / 2, L / 2, 1.5 * L], "body": "block"}}}}
    h5 = prepare(work, name, scene)
    M = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    exact = -1.5 * P * L / M
    r, wall = monitor.run(h5, options(element))
    if r.returncode:
        return None, exact, r.stdout + r.stderr, wall
    return read_csv(h5[:-3] + "_result_points.csv")["top_uz"][-1], exact, r.stdout, wall


def lame_mesh(path, element, n=N_LAME):
    cell = "tet4" if element == "tet4" else "hex8"
    # sectors of 90 degrees around z centred on the diagonal: side0 is the plane y = 0, side1 x = 0
    kw = dict(center=(0, 0, LZ / 2), length=LZ, axis_dir=(0, 0, 1), mid_dir=(1, 1, 0), angle_deg=90.0, n=n, cell=cell)
    meshgen.write_parts(path, [meshgen.cylinder_block("tin", radius=RB, inner=RA / RB, **kw),
                               meshgen.cylinder_block("tout", radius=RC, inner=RB / RC, **kw)])


def lame_scene(msh, nu, element=None):
    mat = {"E": E, "nu": nu}
    bodies = {b: {"mesh": "m", "regions": b, "material": mat, **({"element": element} if element else {})} for b in ("tin", "tout")}
    dirichlet = []
    for b in ("tin", "tout"):
        dirichlet += [{"surface": f"{b}_side0", "components": ["y"]}, {"surface": f"{b}_side1", "components": ["x"]},
                      {"surface": f"{b}_end0", "components": ["z"]}, {"surface": f"{b}_end1", "components": ["z"]}]
    return {"meshes": {"m": msh}, "bodies": bodies,
            "couples": [{"master": "tout_inner", "slave": "tin_curved", "mu": 0.0}],
            "dirichlet": dirichlet,
            "loads": [{"kind": "pressure", "surface": "tin_inner", "value": P}],
            "analysis": {"type": "static"}}


def lame_exact(r, nu, a=RA, b=RC):
    """Lame, plane strain, internal pressure P: radial displacement at r."""
    return (1 + nu) * P * a**2 / (E * (b**2 - a**2)) * ((1 - 2 * nu) * r + b**2 / r)


def inner_radial(h5, body="tin"):
    """Mean radial displacement of the body's vertices on r = RA, and the body (read_body)."""
    b = read_body(h5[:-3] + "_result.h5", body)
    x, u = b["vertices"], b["displacement"]
    r = np.hypot(x[:, 0], x[:, 1])
    on = np.abs(r - RA) < 1e-9
    return np.mean((x[on, 0] * u[on, 0] + x[on, 1] * u[on, 1]) / r[on]), b


def lame(work, name, element, nu, n=N_LAME):
    """Returns (computed mean u_r(RA), exact, monitor, wall)."""
    lame_mesh(os.path.join(work, f"{name}.msh"), element, n)
    h5 = prepare(work, name, lame_scene(f"{name}.msh", nu))
    exact = lame_exact(RA, nu)
    r, wall = monitor.run(h5, options(element))
    if r.returncode:
        return None, exact, r.stdout + r.stderr, wall
    return inner_radial(h5)[0], exact, r.stdout, wall


def case(scene, element, nu, res):
    value, exact, out, wall = res
    reasons, mult_its, static_its = monitor.stats(out)
    error = float("inf") if value is None else abs(value / exact - 1)
    tol = EXACT_TOL if scene == "confined" else LAME_TOL
    ok = bool(error < tol and monitor.converged(reasons))
    ref = ("oedometric modulus M = E(1-nu)/((1+nu)(1-2nu)), exact for every element" if scene == "confined"
           else "Lame thick cylinder 1..2, plane strain, u_r at r = 1")
    note = ""
    if not ok and scene == "lame" and error < float("inf") and monitor.converged(reasons):
        # an error that grows with nu is volumetric locking; tet4's at nu = 0 is its coarser mesh (Kuhn tets)
        note = "locking (use hex8b)" if nu > 0 else "discretization (coarse tets)"
    return dict(category="poisson", value=f"{element} {nu:g} {scene}", x=nu, reasons=reasons, mult_its=mult_its,
                static_its=static_its, error=error, drift=None, wall=wall, ok=ok, ref=ref, note=note,
                scene=scene, element=element, series=f"{scene} {element}")


def cases(work, smoke):
    """Every case of the sweep (smoke: nu = 0.499 only) as dicts: category, value, x (nu), reasons,
    mult_its, static_its, error, drift (None), wall, ok, ref, and note ("locking (use hex8b)"
    where an element is expected to lock), scene, element."""
    rows = []
    for nu in (0.499,) if smoke else NUS:
        for element in ELEMENTS:
            tag = f"{element}_{int(round(nu * 1000))}"
            rows.append(case("confined", element, nu, confined(work, f"c_{tag}", element, nu)))
            rows.append(case("lame", element, nu, lame(work, f"l_{tag}", element, nu)))
    return rows


def plot_error(path, rows):
    """Error against 0.5 - nu (log-log: the sweep 0 ... 0.499 spreads over 0.5 ... 0.001)."""
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return
    fig, ax = plt.subplots(figsize=(7, 4.5))
    for scene, style in (("lame", "-"), ("confined", ":")):
        for element, marker in zip(ELEMENTS, "osd^"):
            rs = [r for r in rows if r["scene"] == scene and r["element"] == element]
            ax.loglog([0.5 - r["x"] for r in rs], [max(r["error"], 1e-17) for r in rs], marker + style, label=f"{scene} {element}")
    ax.axhline(LAME_TOL, color="k", lw=0.8, ls="--", label="lame pass")
    ax.axhline(EXACT_TOL, color="k", lw=0.8, ls="-.", label="confined pass")
    ax.invert_xaxis()
    ax.set_xlabel("0.5 - nu")
    ax.set_ylabel("relative error")
    ax.set_title("Poisson's ratio (bench/extremes_poisson.py)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2, loc="center left")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    print(f"\nplot: {path}")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--smoke", action="store_true", help="nu = 0.499 only (one case per element and scene)")
    ap.add_argument("--plot", default=os.path.join(ROOT, "docs", "extremes-poisson.png"), help="error against nu ('' for none)")
    a = ap.parse_args()
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="mbc_poisson_") as work:
        rows = cases(work, a.smoke)
    print(f"{'scene':>8} {'element':>7} {'nu':>6} {'reasons':>16} {'mult':>5} {'static':>6} {'error':>10} {'wall':>6} {'':>5}")
    for r in rows:
        print(f"{r['scene']:>8} {r['element']:>7} {r['x']:6g} {','.join(r['reasons']):>16} {r['mult_its']:5d} {r['static_its']:6d} "
              f"{r['error']:10.2e} {r['wall']:6.2f} {'pass' if r['ok'] else 'FAIL':>5} {r['note']}")
    failed = [r for r in rows if not r["ok"]]
    print(f"\n{len(rows) - len(failed)} of {len(rows)} cases pass ({time.perf_counter() - t0:.0f} s)"
          + (": failing " + ", ".join(r["value"] + (f" [{r['note']}]" if r["note"] else "") for r in failed) if failed else ""))
    if a.plot and not a.smoke:
        plot_error(a.plot, rows)
    return 0 if all(r["ok"] or r["note"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
