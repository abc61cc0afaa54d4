"""Readers for mbcontact's result files (h5py only: never import petsc4py beside it).

The solver writes one HDF5 file `<output>.h5` (layout in docs/scene.md, Output): per body
`/bodies/<name>/vertices`, `cells` and `step_<k>/displacement`, `stress`; per output step the
contact points in `/contact/step_<k>`; the output times in `/time`. Vertices and cells are in the
scene's order (as mbcontact-prep wrote them), whatever the rank count.
"""
import csv

import numpy as np


def read_csv(path):
    """A CSV written by the solver as a dict of column name -> numpy array."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, data = rows[0], np.array(rows[1:], dtype=float).reshape(-1, len(rows[0]))
    return {name: data[:, i] for i, name in enumerate(header)}


def _steps(group):
    """The step_<k> subgroups of a group, by k."""
    return sorted((n for n in group if n.startswith("step_")), key=lambda n: int(n[5:]))


def output_times(path):
    """Times of the output steps."""
    import h5py

    with h5py.File(path, "r") as f:
        return f["time"][...]


def output_cuts(path):
    """Step halvings before each output step (0: none; a result file older than the step
    control has no /cuts and gives zeros)."""
    import h5py

    with h5py.File(path, "r") as f:
        n = len(f["time"])
        return f["cuts"][...] if "cuts" in f else np.zeros(n, dtype=int)


def body_names(path):
    """Names of the bodies in the result file, in the scene's order."""
    import h5py

    with h5py.File(path, "r") as f:
        if "bodies" not in f:
            return []
        return sorted(f["bodies"], key=lambda n: int(f["bodies"][n].attrs["index"]))


# stress components in the file and from read_body: XDMF's Tensor6 order (what ParaView shows)
STRESS_COMPONENTS = ("xx", "xy", "xz", "yy", "yz", "zz")
_TENSOR6_OF_VOIGT = [0, 3, 5, 1, 4, 2]  # format_version 1 files hold xx yy zz xy yz xz


def stress_component(stress, name):
    """Column `name` (e.g. "zz" or "yx") of a stress array from read_body."""
    key = name if name in STRESS_COMPONENTS else name[::-1]
    return stress[:, STRESS_COMPONENTS.index(key)]


def read_body(path, body, step=-1):
    """Vertices (nv, 3), cells (nc, 4|8; XDMF/VTK vertex order), displacement (nv, 3) and stress
    (nc, 6: xx xy xz yy yz zz, XDMF's Tensor6 order; STRESS_COMPONENTS) of one body at an output
    step (index into the output steps, negative from the end), with its time and the number of
    output steps."""
    import h5py

    with h5py.File(path, "r") as f:
        version = int(f.attrs.get("format_version", 1))
        if f"bodies/{body}" not in f:
            raise KeyError(f"{path}: no body '{body}' (bodies: {', '.join(f['bodies']) if 'bodies' in f else 'none'})")
        g = f["bodies"][body]
        steps = _steps(g)
        out = {"vertices": g["vertices"][...], "cells": g["cells"][...], "cell_type": g.attrs["cell_type"].decode(),
               "num_steps": len(steps)}
        if steps:
            s = g[steps[step]]
            out["time"] = float(s.attrs["time"])
            for name in ("displacement", "stress"):
                if name in s:
                    out[name] = s[name][...]
            if "stress" in out and version < 2:
                out["stress"] = out["stress"][:, _TENSOR6_OF_VOIGT]
    return out


def read_contact(path, step=-1):
    """Datasets of the contact points at an output step (position, reference, normal, force,
    multiplier, pressure, traction, gap, slip, area, state, couple; with bonded couples bonded
    and break_time) as numpy arrays, with the step's time."""
    import h5py

    with h5py.File(path, "r") as f:
        steps = _steps(f["contact"])
        g = f["contact"][steps[step]]
        out = {k: v[...] for k, v in g.items()}
        out["time"] = float(g.attrs["time"])
    return out


def read_modes(path):
    """A modal analysis's /modes: frequency [Hz], period [s], participation (n, 3: Gamma_d =
    phi^T M iota_d, phi mass-normalised), effective_mass (n, 3: Gamma_d^2) and total_mass (3: the
    mass along x, y, z the modes can carry, the held DOFs' left out)."""
    import h5py

    with h5py.File(path, "r") as f:
        if "modes" not in f:
            raise KeyError(f"{path}: no /modes (not the result of a modal analysis)")
        g = f["modes"]
        out = {k: g[k][...] for k in ("frequency", "period", "participation", "effective_mass")}
        out["total_mass"] = g.attrs["total_mass"][...]
    return out


def point_history(path, point):
    """A point's history from <output>_points.csv: t, u (n, 3) and, in dynamic analyses, the
    absolute displacement, velocity and acceleration (relative plus the ground's) as abs_u,
    abs_v, abs_a (n, 3)."""
    c = read_csv(path)
    if f"{point}_ux" not in c:
        names = sorted({k.rsplit("_", 1)[0] for k in c if k.endswith("_ux") and "_abs" not in k})
        raise KeyError(f"{path}: no point '{point}' (points: {', '.join(names)})")
    out = {"t": c["t"], "u": np.column_stack([c[f"{point}_u{x}"] for x in "xyz"])}
    for q in "uva":
        if f"{point}_abs_{q}x" in c:
            out[f"abs_{q}"] = np.column_stack([c[f"{point}_abs_{q}{x}"] for x in "xyz"])
    return out


def log_view_times(text, events):
    """Seconds per phase from a -log_view report: events maps a phase name to a PETSc event
    name or a tuple of names (summed); absent events count 0. An event logged in several stages
    (the search and the output run in the main stage and in the analysis's) is summed over them."""
    import re
    times = {}
    for name, ev in events.items():
        total = 0.0
        for e in ev if isinstance(ev, tuple) else (ev,):
            total += sum(float(t) for t in re.findall(rf"^{e}\s+\d+\s+\S+\s+(\S+)", text, re.M))
        times[name] = total
    return times
