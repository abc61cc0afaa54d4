#!/usr/bin/python3
"""Results of the Hertz cylinder pair against Hertz theory and the paper (h5py only: never
import petsc4py beside it).

  meshes/hertz/report.py RESULT_PREFIX      e.g. /tmp/hz/hertz_result
"""
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), "python"))
from mbcontact.results import read_body, read_contact, read_csv  # noqa: E402

R, E, NU, LENGTH = 5.0, 210000.0, 0.3, 1.0
X_PAPER = np.array([0.0, 0.0626, 0.1252, 0.1877, 0.2503])
PAPER = {"P": 1234.42, "b": 0.188, "p_max": 4136.6,  # the paper's FE results (P: its Hertz reference load)
         "upper": np.array([-0.014948, -0.015338, -0.016463, -0.018475, -0.019941])}
ANSYS = np.array([-0.015046, -0.015419, -0.016580, -0.018538, -0.020046])  # upper surface; the lower mirrors it about -0.015
HERTZ_PAPER = {"P": 1234.42, "b": 0.185, "p_max": 4256.4}


def hertz_line(P, r1=R, r2=R, e=E, nu=NU):
    """Half-width b and peak pressure of two parallel cylinders under P per unit length."""
    estar = e / (2 * (1 - nu**2))
    rstar = r1 * r2 / (r1 + r2)
    b = np.sqrt(4 * P * rstar / (np.pi * estar))
    return b, 2 * P / (np.pi * b)


def hertz_point(P, r, e=E, nu=NU):
    """Contact radius and peak pressure of a sphere on a half-space of the same material."""
    estar = e / (2 * (1 - nu**2))
    a = (3 * P * r / (4 * estar)) ** (1 / 3)
    return a, 3 * P / (2 * np.pi * a**2)


def half_width(x, p):
    """Edge of the contact from nodal pressures (x >= 0 sorted): p^2 = p0^2 (1 - x^2 / b^2) is
    linear in x^2, so the last two loaded nodes extrapolate to p = 0."""
    k = np.nonzero(p > 0)[0][-1]
    if k == 0:
        return x[1]
    x1, x2, q1, q2 = x[k - 1] ** 2, x[k] ** 2, p[k - 1] ** 2, p[k] ** 2
    return np.sqrt(x2 + q2 * (x2 - x1) / (q1 - q2)) if q1 > q2 else x[k]


def half_width_fit(x, p):
    """Edge of the contact from the least-squares line of p^2 against x^2 over the loaded nodes
    with p > p0 / 3 (as the sphere's a, sphere_results): unlike half_width it does not hang on
    the last loaded node, which jumps by a whole element when the first node beyond the edge
    carries a small pressure (its dual shape function reaches into the zone)."""
    use = p > p[0] / 3
    if use.sum() < 2:
        return half_width(x, p)
    slope, intercept = np.polyfit(x[use] ** 2, p[use] ** 2, 1)
    return np.sqrt(-intercept / slope)


def contact_points(prefix, step=-1):
    return read_contact(prefix + ".h5", step)


def surface_uy(prefix, body, x):
    """u_y of a body's arc (z = 0) at abscissae x, interpolated between its nodes."""
    b = read_body(prefix + ".h5", body)
    v, u = b["vertices"], b["displacement"]
    centre = np.array([0.0, R if body == "upper" else -R])
    on = (np.abs(np.linalg.norm(v[:, :2] - centre, axis=1) - R) < 1e-6) & (np.abs(v[:, 2]) < 1e-9)
    o = np.argsort(v[on, 0])
    return np.interp(x, v[on, 0][o], u[on, 1][o])


def cylinder_results(prefix):
    """P per unit length (both halves), b, p_max, surface displacements at the paper's x."""
    c = read_csv(prefix + "_contact.csv")
    P = 2 * c["normal_force"][-1] / LENGTH  # the quarter model carries half the load
    pts = contact_points(prefix)  # reference coordinates: Hertz theory is linear (the surface
    x, z, p = pts["reference"][:, 0], pts["reference"][:, 2], pts["pressure"]  # moves inward by ~1.5e-3 mm at x = b)
    row = np.abs(z) < 1e-6
    o = np.argsort(x[row])
    xs, ps = x[row][o], p[row][o]
    return {"P": P, "b": half_width(xs, ps), "b_fit": half_width_fit(xs, ps), "p_max": ps[0] if xs[0] < 1e-9 else np.interp(0, xs, ps),
            "upper": surface_uy(prefix, "upper", X_PAPER), "lower": surface_uy(prefix, "lower", X_PAPER),
            "points": int(row.sum()), "loaded": int((ps > 0).sum())}


def sphere_results(prefix):
    """Load P (the quarter model carries a quarter), contact radius a and peak pressure p0."""
    c = read_csv(prefix + "_contact.csv")
    P = 4 * c["normal_force"][-1]
    pts = contact_points(prefix)
    r = np.linalg.norm(pts["reference"][:, :2], axis=1)
    p = pts["pressure"]
    p0 = p[np.argmin(r)]
    # p^2 = p0^2 (1 - r^2 / a^2) is linear in r^2: least squares over the loaded points away from
    # the edge (p > p0 / 3), where the nodal averages follow the ellipsoid
    use = p > p0 / 3
    slope, intercept = np.polyfit(r[use] ** 2, p[use] ** 2, 1)
    return {"P": P, "a": np.sqrt(-intercept / slope), "p0": p0, "a_edge": r[p > 0].max(), "loaded": int((p > 0).sum())}


def errors(res):
    """Relative errors against Hertz for the computed P, and of the upper surface against ANSYS."""
    b, pmax = hertz_line(res["P"])
    return {"b": res["b"] / b - 1, "b_fit": res["b_fit"] / b - 1, "p_max": res["p_max"] / pmax - 1,
            "upper": np.abs(res["upper"] / ANSYS - 1).max(), "lower": np.abs(res["lower"] / (-0.03 - ANSYS) - 1).max()}


def print_report(res, title="Hertz: two parallel cylinders"):
    b, pmax = hertz_line(res["P"])
    print(f"\n{title}: R1 = R2 = {R} mm, E = {E:g} MPa, nu = {NU}, -0.03 mm imposed\n")
    print(f"{'quantity':34s} {'mbcontact':>11s} {'Hertz(P)':>11s} {'error':>8s} {'paper':>11s} {'paper err':>9s}")
    print(f"{'P per unit length [N/mm]':34s} {res['P']:11.2f} {'':>11s} {'':>8s} {PAPER['P']:11.2f}")
    for key, ref, unit in (("b", b, "mm"), ("p_max", pmax, "MPa")):
        paper_err = PAPER[key] / HERTZ_PAPER[key] - 1
        print(f"{key + ' [' + unit + ']':34s} {res[key]:11.5g} {ref:11.5g} {res[key] / ref - 1:8.2%} {PAPER[key]:11.5g} {paper_err:9.2%}")
    print(f"\n{'x [mm]':>8s} {'upper u_y':>11s} {'ANSYS':>11s} {'error':>8s} {'paper':>11s} {'lower u_y':>11s} {'ANSYS':>11s} {'error':>8s}")
    for i, x in enumerate(X_PAPER):
        lo = -0.03 - ANSYS[i]
        print(f"{x:8.4f} {res['upper'][i]:11.6f} {ANSYS[i]:11.6f} {res['upper'][i] / ANSYS[i] - 1:8.2%} {PAPER['upper'][i]:11.6f} "
              f"{res['lower'][i]:11.6f} {lo:11.6f} {res['lower'][i] / lo - 1:8.2%}")


def summary(res, tol=0.005):
    """One line on what this run measured: the errors against Hertz for its own load, and whether
    they are within tol."""
    err = errors(res)
    within = all(abs(err[k]) < tol for k in ("b", "p_max"))
    return (f"Measured: b {err['b']:+.2%}, p_max {err['p_max']:+.2%} of Hertz for the computed P = {res['P']:.1f} N/mm "
            f"(b / R = {res['b'] / R:.4f}); {'both' if within else 'not both'} within {tol:.1%}. Surface u_y within "
            f"{max(err['upper'], err['lower']):.2%} of ANSYS. Pressure = contact force / reference (undeformed) area.")


if __name__ == "__main__":
    res = cylinder_results(sys.argv[1])
    print_report(res)
    print("\n" + summary(res))
