#!/usr/bin/python3
"""Sliding and opening of the joints and the base of the dam (meshes/dam/build.py), from the
solver's contact results (h5py only: never import petsc4py beside it).

  meshes/dam/report.py OUTDIR/dam_result [--json] [--spectrum POINT [--damping 0.05]] [--plots DIR]

Per couple (the base, each joint), over the whole run and at the end: largest opening (gap) and
sliding (accumulated tangential slip), the fractions of points open and slipping, the resultant
force on the master side; for the base the vertical and horizontal resultants against the dam's
weight W and the hydrostatic thrust T, and the sliding factor of safety mu W / T (design value)
and mu N / |F_t| from the computed base resultant (its smallest value over a dynamic run). Per
monolith (from the contact points of the last output) the base's opening and sliding.

The seismic results engineers report: with `envelope` in the output fields, per body the largest
principal stress over the run, where and when; the absolute acceleration of a point (relative
plus the ground's, <prefix>_points.csv) and its 5 %-damped response spectrum (--spectrum POINT:
<prefix>_spectrum_<POINT>.csv, and a plot with --plots); with --plots DIR PNG files of the base and
joints' opening and sliding histories, the point's acceleration and its spectrum. A modal result
(/modes) gives its table of frequencies and effective masses instead.

Everything per step comes from <prefix>_contact.csv; only the per-monolith split reads the
per-point file, through contact_points() alone (the collective <prefix>.h5 or the older
<prefix>_contact.h5).
"""
import argparse
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), "python"))
from mbcontact.records import response_spectrum  # noqa: E402
from mbcontact.results import point_history, read_csv, read_modes  # noqa: E402

PERIODS = np.geomspace(0.02, 5.0, 120)  # s: the range of a dam's modes and of a record's content


def contact_points(prefix, step=-1):
    """Per-point datasets of one output step (reference, gap, slip, state, couple, force, ...):
    the only access to the per-point contact file. Reads the collective result file
    `<prefix>.h5` (group /contact/step_<k>) where it has one, else `<prefix>_contact.h5`."""
    import h5py

    for path, group in ((prefix + ".h5", "contact"), (prefix + "_contact.h5", None)):
        if not os.path.exists(path):
            continue
        with h5py.File(path, "r") as f:
            if group and group not in f:
                continue
            parent = f[group] if group else f
            names = sorted((n for n in parent if n.startswith("step_")), key=lambda n: int(n.split("_")[1]))
            g = parent[names[step]]
            out = {k: v[...] for k, v in g.items()}
            out["time"] = float(g.attrs["time"])
            return out
    raise OSError(f"no contact points under {prefix} (.h5 or _contact.h5)")


def contact_point_steps(prefix):
    """Every output step's per-point datasets (contact_points() for each), oldest first."""
    import h5py

    for path, group in ((prefix + ".h5", "contact"), (prefix + "_contact.h5", None)):
        if os.path.exists(path):
            with h5py.File(path, "r") as f:
                if group and group not in f:
                    continue
                n = sum(1 for name in (f[group] if group else f) if name.startswith("step_"))
            return [contact_points(prefix, i) for i in range(n)]
    return []


def scene_couples(prefix):
    """{k: the couple's YAML mapping} from the scene build.py wrote beside the results (dam.yaml):
    mu, cohesion (a joint law's, if the scene has one), uplift."""
    import yaml

    path = os.path.join(os.path.dirname(os.path.abspath(prefix)), "dam.yaml")
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        doc = yaml.safe_load(f)
    return {int(c.get("k", i + 1)): c for i, c in enumerate(doc.get("couples") or [])}


def joint_planes(prefix, info, hist):
    """The sliding factor of safety of the base and each lift joint over time (USACE EM 1110-2-2100,
    FERC chapter III): FS = (c A_bonded + mu N') / T, N' the effective normal force (the contact's
    normal resultant: the uplift acts on the faces already), T the shear resultant (horizontal
    planes: |(Fx, Fy)|), c the couple's `cohesion` (0 without), A_bonded the area of its points
    still bonded (the per-point `bonded` output of a joint law; 0 without); and the cracked length
    from the heel (the first point in compression along x) at every output step."""
    couples = scene_couples(prefix)
    steps = contact_point_steps(prefix)
    planes = {}
    for k, name in info["couples"].items():
        if not (k == 1 or str(name).startswith("lift")) or k not in hist:
            continue
        h = hist[k]
        spec = couples.get(k, {})
        mu = float(spec.get("mu", info["params"]["mu_base"] if k == 1 else info["params"]["mu_joint"]))
        c = float(spec.get("cohesion", 0.0))
        up = spec.get("uplift") or {}
        length = float(up.get("length", info["params"]["crest"] + info["params"]["slope"] * (info["params"]["height"] - info["params"]["crest"] / info["params"]["slope"])))
        x0 = float((up.get("origin") or [0.0])[0])
        times, abond, crack = [], [], []
        for st in steps:
            mine = st["couple"].reshape(-1) == k
            area = st["area"].reshape(-1)[mine]
            bonded = st["bonded"].reshape(-1)[mine] if "bonded" in st else np.zeros(len(area))
            x = st["reference"][mine][:, 0] - x0
            closed = st["pressure"].reshape(-1)[mine] > 0
            times.append(st["time"])
            abond.append(float(area[bonded != 0].sum()))
            crack.append(float(np.clip(x[closed].min(), 0, length)) if closed.any() else length)
        times, abond = np.array(times), np.array(abond)
        # A_bonded at each CSV step: the last output at or before it (0 before the first)
        idx = np.searchsorted(times, h["t"] + 1e-12, side="right") - 1
        ab = np.where(idx >= 0, abond[np.maximum(idx, 0)] if len(abond) else 0.0, 0.0)
        N, T = h["normal_force"], np.hypot(h["fx"], h["fy"])
        with np.errstate(divide="ignore", invalid="ignore"):
            fs = np.where(T > 0, (c * ab + mu * N) / T, np.inf)
        i = int(np.argmin(fs))
        planes[k] = {"name": name, "mu": mu, "cohesion": c, "t": h["t"].tolist(), "fs": fs.tolist(),
                     "normal": N.tolist(), "shear": T.tolist(), "bonded_area": ab.tolist(),
                     "uplift": (h["uplift"] if "uplift" in h else np.zeros_like(N)).tolist(),
                     "fs_final": float(fs[-1]), "fs_min": float(fs[i]), "fs_min_time": float(h["t"][i]),
                     "crack_times": times.tolist(), "cracked_length": crack, "length": length}
    return planes


def scene_info(prefix):
    """The parameters build.py wrote beside the scene (dam.json): loads, couples, friction."""
    folder = os.path.dirname(os.path.abspath(prefix))
    with open(os.path.join(folder, "dam.json")) as f:
        info = json.load(f)
    info["couples"] = {int(k): v for k, v in info["couples"].items()}
    return info


def couple_histories(prefix):
    """{k: {column: array over the steps}} from the contact CSV."""
    c = read_csv(prefix + "_contact.csv")
    return {int(k): {name: col[c["couple"] == k] for name, col in c.items()} for k in np.unique(c["couple"])}


def summarize(prefix):
    """The report as a dict (see the module docstring)."""
    info = scene_info(prefix)
    p = info["params"]
    n = p["monoliths"]
    W, T = n * info["weight"], n * info["thrust"]
    hist = couple_histories(prefix)
    eq = info.get("eq_start")
    out = {"dofs": info["dofs"], "analysis": info["analysis"], "weight": W, "thrust": T, "couples": {}}
    for k, h in hist.items():
        pts = np.maximum(h["points"], 1)
        with np.errstate(invalid="ignore"):
            slip = np.nan_to_num(h["max_slip"], nan=0.0)
        row = {"name": info["couples"].get(k, f"couple {k}"),
               "mu": p["mu_base"] if k == 1 else p["mu_joint"],
               "points": int(h["points"][-1]),
               "max_opening": float(np.max(h["max_opening"])), "max_sliding": float(np.max(slip)),
               "final_opening": float(h["max_opening"][-1]), "final_sliding": float(slip[-1]),
               "open_fraction": float(h["separated"][-1] / pts[-1]), "slip_fraction": float(h["slip"][-1] / pts[-1]),
               "max_open_fraction": float(np.max(h["separated"] / pts)), "max_slip_fraction": float(np.max(h["slip"] / pts)),
               "force": [float(h["fx"][-1]), float(h["fy"][-1]), float(h["fz"][-1])],
               "normal_force": float(h["normal_force"][-1])}
        if k == 1:
            N, Ft = h["fz"], np.hypot(h["fx"], h["fy"])
            with np.errstate(divide="ignore", invalid="ignore"):
                fs = np.where(Ft > 0, row["mu"] * N / Ft, np.inf)
            during = h["t"] >= eq if eq is not None else np.ones_like(N, bool)
            U = float(h["uplift"][-1]) if "uplift" in h else 0.0  # the base's uplift (build.py --uplift)
            row.update(vertical_over_weight=float(N[-1] / W), horizontal_over_thrust=float(-h["fx"][-1] / T),
                       uplift=U, vertical_over_weight_minus_uplift=float(N[-1] / (W - U)) if W > U else float("nan"),
                       design_safety=row["mu"] * (W - U) / T, safety_final=float(fs[-1]),
                       safety_min=float(np.min(fs[during])) if during.any() else float(fs[-1]),
                       safety_min_time=float(h["t"][during][np.argmin(fs[during])]) if during.any() else float(h["t"][-1]))
        out["couples"][k] = row
    out["monoliths"] = _per_monolith(prefix, p)
    out["planes"] = joint_planes(prefix, info, hist)
    return out


def _per_monolith(prefix, p):
    """Base opening and sliding per monolith at the last output, from the contact points of the
    base couple: a point belongs to the monolith whose span holds its reference y (points on a
    joint line, one per neighbour, count for both)."""
    try:
        pts = contact_points(prefix)
    except (OSError, KeyError, IndexError):
        return []
    base = pts["couple"].reshape(-1) == 1
    y = pts["reference"][base][:, 1]
    gap, state = pts["gap"].reshape(-1)[base], pts["state"].reshape(-1)[base]
    slip = np.linalg.norm(np.nan_to_num(pts["slip"][base]), axis=1)
    rows = []
    for k in range(1, p["monoliths"] + 1):
        lo, hi = (k - 1) * p["width"], k * p["width"]
        m = (y >= lo - 1e-9 * hi) & (y <= hi + 1e-9 * hi)
        rows.append({"monolith": k, "points": int(m.sum()), "max_opening": float(gap[m].max()) if m.any() else 0.0,
                     "max_sliding": float(slip[m].max()) if m.any() else 0.0,
                     "open_fraction": float(np.mean(state[m] == 0)) if m.any() else 0.0,
                     "slip_fraction": float(np.mean(state[m] == 2)) if m.any() else 0.0})
    return rows


def text(r):
    lines = [f"dam: {len(r['monoliths']) or '?'} monoliths, {r['dofs']} DOFs, {r['analysis']} analysis; "
             f"W = {r['weight']:.6e} N, T = {r['thrust']:.6e} N (W / T = {r['weight'] / r['thrust']:.3f})",
             f"{'couple':<16} {'mu':>5} {'points':>6} {'max open [m]':>13} {'max slide [m]':>14} "
             f"{'open %':>7} {'slip %':>7} {'Fx [N]':>13} {'Fy [N]':>13} {'Fz [N]':>13}"]
    for k, c in sorted(r["couples"].items()):
        lines.append(f"{c['name']:<16} {c['mu']:5.2f} {c['points']:6d} {c['max_opening']:13.4e} {c['max_sliding']:14.4e} "
                     f"{100 * c['open_fraction']:7.1f} {100 * c['slip_fraction']:7.1f} "
                     f"{c['force'][0]:13.5e} {c['force'][1]:13.5e} {c['force'][2]:13.5e}")
    b = r["couples"].get(1)
    if b:
        lines += [f"base: vertical resultant / W = {b['vertical_over_weight']:.6f}, horizontal / T = {b['horizontal_over_thrust']:.6f}"
                  + (f", uplift U = {b['uplift']:.6e} N, vertical / (W - U) = {b['vertical_over_weight_minus_uplift']:.6f}" if b["uplift"] else ""),
                  f"sliding factor of safety: design mu {'(W - U)' if b['uplift'] else 'W'} / T = {b['design_safety']:.3f}; computed mu N / |F_t| = "
                  f"{b['safety_final']:.3f} at the end, {b['safety_min']:.3f} at its smallest (t = {b['safety_min_time']:.3f} s)"]
    if r.get("planes"):
        lines.append(f"{'joint plane':<20} {'N_eff [N]':>12} {'T [N]':>12} {'uplift [N]':>12} {'c A_b [N]':>12} "
                     f"{'FS end':>7} {'FS min':>7} {'at t':>8} {'cracked [m]':>11} {'max':>7} {'/ length':>8}")
        for k, q in sorted(r["planes"].items()):
            crack = q["cracked_length"]
            lines.append(f"{q['name']:<20} {q['normal'][-1]:12.5e} {q['shear'][-1]:12.5e} {q['uplift'][-1]:12.5e} "
                         f"{q['cohesion'] * q['bonded_area'][-1]:12.5e} {q['fs_final']:7.3f} {q['fs_min']:7.3f} "
                         f"{q['fs_min_time']:8.3f} {crack[-1] if crack else float('nan'):11.3f} "
                         f"{max(crack) if crack else float('nan'):7.3f} {q['length']:8.3f}")
        lines.append("FS = (c A_bonded + mu N_eff) / T per joint plane (uplift on the faces: N_eff is the contact's "
                     "normal force); cracked: from the heel to the first point in compression")
    if r["monoliths"]:
        lines.append(f"{'monolith':<9} {'points':>6} {'base open [m]':>14} {'base slide [m]':>15} {'open %':>7} {'slip %':>7}  (last output)")
        for m in r["monoliths"]:
            lines.append(f"m{m['monolith']:<8} {m['points']:6d} {m['max_opening']:14.4e} {m['max_sliding']:15.4e} "
                         f"{100 * m['open_fraction']:7.1f} {100 * m['slip_fraction']:7.1f}")
    return "\n".join(lines)


def envelope(prefix):
    """Per body the largest principal stress over the run (the last output's envelope), its time
    and the centre of its cell; [] without the `envelope` field."""
    import h5py

    out = []
    with h5py.File(prefix + ".h5", "r") as f:
        n = int(f.attrs["num_outputs"])
        for name in sorted(f.get("bodies", {}), key=lambda b: int(f["bodies"][b].attrs["index"])):
            g = f["bodies"][name]
            step = g.get(f"step_{n - 1}")
            if step is None or "max_principal_stress" not in step:
                continue
            s1, t1 = step["max_principal_stress"][...], step["max_principal_stress_time"][...]
            c = int(np.argmax(s1))
            centre = g["vertices"][...][g["cells"][c]].mean(axis=0)
            out.append({"body": name, "max_principal_stress": float(s1[c]), "time": float(t1[c]), "cell": c,
                        "centre": [float(x) for x in centre]})
    return out


def spectrum(prefix, point, damping=0.05):
    """The response spectrum (PSA, SA, SD per component x y z) of a point's absolute acceleration."""
    h = point_history(prefix + "_points.csv", point)
    if "abs_a" not in h:
        raise KeyError(f"{prefix}_points.csv: no absolute acceleration of '{point}' (a dynamic analysis writes it)")
    out = {"T": PERIODS, "damping": damping, "t": h["t"], "a": h["abs_a"]}
    for i, c in enumerate("xyz"):
        s = response_spectrum(h["t"], h["abs_a"][:, i], PERIODS, damping)
        out[c] = s
    return out


def write_spectrum(prefix, point, sp):
    path = f"{prefix}_spectrum_{point}.csv"
    with open(path, "w") as f:
        f.write("T," + ",".join(f"PSA_{c},SA_{c},SD_{c}" for c in "xyz") + "\n")
        for i, T in enumerate(sp["T"]):
            f.write(f"{T:.6g}," + ",".join(f"{sp[c]['PSA'][i]:.6e},{sp[c]['SA'][i]:.6e},{sp[c]['SD'][i]:.6e}" for c in "xyz") + "\n")
    return path


def plots(prefix, folder, point=None, sp=None):
    """PNG files: the couples' largest opening and sliding over time, a point's absolute
    acceleration and its spectrum. Returns their paths."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(folder, exist_ok=True)
    paths = []
    if os.path.exists(prefix + "_contact.csv"):
        info = scene_info(prefix)
        fig, ax = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
        for k, h in couple_histories(prefix).items():
            name = info["couples"].get(k, f"couple {k}")
            ax[0].plot(h["t"], h["max_opening"] * 1e3, label=name)
            ax[1].plot(h["t"], np.nan_to_num(h["max_slip"]) * 1e3, label=name)
        ax[0].set_ylabel("largest opening [mm]")
        ax[1].set_ylabel("largest sliding [mm]")
        ax[1].set_xlabel("t [s]")
        ax[0].legend(fontsize=7)
        paths.append(os.path.join(folder, "joints.png"))
        fig.savefig(paths[-1], dpi=100)
        plt.close(fig)
    if sp is not None:
        fig, ax = plt.subplots(2, 1, figsize=(8, 7))
        for i, c in enumerate("xyz"):
            if np.abs(sp["a"][:, i]).max() > 0:
                ax[0].plot(sp["t"], sp["a"][:, i], label=c)
                ax[1].loglog(sp["T"], sp[c]["PSA"], label=f"{c} (PSA)")
        ax[0].set_xlabel("t [s]")
        ax[0].set_ylabel(f"{point}: absolute acceleration")
        ax[1].set_xlabel("period [s]")
        ax[1].set_ylabel(f"PSA, {100 * sp['damping']:g} % damping")
        ax[0].legend()
        ax[1].legend()
        paths.append(os.path.join(folder, f"spectrum_{point}.png"))
        fig.savefig(paths[-1], dpi=100)
        plt.close(fig)
    return paths


def modal_text(prefix):
    m = read_modes(prefix + ".h5")
    tot = m["total_mass"]
    lines = [f"{'mode':>4} {'f [Hz]':>10} {'T [s]':>9} {'m_x %':>7} {'m_y %':>7} {'m_z %':>7}"]
    for i, f in enumerate(m["frequency"]):
        e = 100 * m["effective_mass"][i] / np.where(tot > 0, tot, 1)
        lines.append(f"{i + 1:4d} {f:10.4f} {m['period'][i]:9.4f} {e[0]:7.2f} {e[1]:7.2f} {e[2]:7.2f}")
    return "\n".join(lines)


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("prefix", help="result prefix, e.g. OUTDIR/dam_result")
    ap.add_argument("--json", action="store_true", help="print the report as JSON")
    ap.add_argument("--spectrum", metavar="POINT", help="response spectrum of this output point's absolute acceleration")
    ap.add_argument("--damping", type=float, default=0.05, help="the spectrum's damping ratio (default 0.05)")
    ap.add_argument("--plots", metavar="DIR", help="write PNG plots into DIR")
    a = ap.parse_args()
    import h5py
    modal = False
    if os.path.exists(a.prefix + ".h5"):
        with h5py.File(a.prefix + ".h5", "r") as f:
            modal = "modes" in f
    if modal:
        print(modal_text(a.prefix))
        sys.exit(0)
    r = summarize(a.prefix)
    r["envelope"] = envelope(a.prefix) if os.path.exists(a.prefix + ".h5") else []
    sp = None
    if a.spectrum:
        sp = spectrum(a.prefix, a.spectrum, a.damping)
        r["spectrum"] = {"point": a.spectrum, "file": write_spectrum(a.prefix, a.spectrum, sp)}
        for c in "xyz":
            i = int(np.argmax(sp[c]["PSA"]))
            r["spectrum"][c] = {"peak_PSA": float(sp[c]["PSA"][i]), "at_period": float(sp["T"][i]),
                                "peak_abs_acceleration": float(np.abs(sp["a"][:, "xyz".index(c)]).max())}
    if a.plots:
        r["plots"] = plots(a.prefix, a.plots, a.spectrum, sp)
    if a.json:
        print(json.dumps(r, indent=1))
    else:
        print(text(r))
        for e in r["envelope"]:
            print(f"{e['body']}: largest principal stress {e['max_principal_stress']:.4e} at t = {e['time']:.3f} s, "
                  f"cell {e['cell']} at ({e['centre'][0]:.1f}, {e['centre'][1]:.1f}, {e['centre'][2]:.1f})")
        if sp is not None:
            for c in "xyz":
                s = r["spectrum"][c]
                if s["peak_abs_acceleration"] > 0:
                    print(f"{a.spectrum} {c}: peak absolute acceleration {s['peak_abs_acceleration']:.4g}, "
                          f"{100 * a.damping:g} % spectrum peak PSA {s['peak_PSA']:.4g} at T = {s['at_period']:.3f} s")
            print(f"spectrum: {r['spectrum']['file']}")
        for p in r.get("plots", []):
            print(f"plot: {p}")
