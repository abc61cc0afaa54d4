#!/usr/bin/python3
"""The Hertz cylinder pair (build.py's quarter models and scene) as a CalculiX model, and its
results read back as report.py reads mbcontact's: P, b and p_max from the same estimators.

The same hex meshes (build.quarter_disc + build.extrude, one element through z), C3D8I (or
C3D8), u_x = 0 on both x = 0 faces, u_z = 0 on both ends (plane strain), lower flat face fixed
in y, upper flat face moved by -DELTA in y; frictionless face-to-face contact (slave lower_arc,
master upper_arc, as mbcontact's couple) with a linear pressure-overclosure of slope `penalty`
[MPa/mm]; one *STATIC step, NLGEOM off (ccx's default).

  meshes/hertz/ccx.py OUTDIR [--hc 0.04] [--element C3D8I] [--penalty 3e8]
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import build  # noqa: E402
import report  # noqa: E402

CCX = shutil.which("ccx")
# C3D8 faces in CalculiX's (Abaqus') numbering; node order as Gmsh's hex8
FACES = {1: (0, 1, 2, 3), 2: (4, 7, 6, 5), 3: (0, 4, 5, 1), 4: (1, 5, 6, 2), 5: (2, 6, 7, 3), 6: (3, 7, 4, 0)}


def version():
    if not CCX:
        return None
    out = subprocess.run([CCX, "-v"], capture_output=True, text=True).stdout
    m = re.search(r"Version\s+(\S+)", out)
    return m.group(1) if m else out.strip()


def _lines(ids, per=16):
    ids = list(ids)
    return "".join(", ".join(str(i) for i in ids[k:k + per]) + ",\n" for k in range(0, len(ids), per))


def write_inp(path, hc, element="C3D8I", penalty=3e8, delta=build.DELTA, increment=1.0):
    """Writes the model; returns (number of nodes, slave node ids, node coordinates (1-based by id))."""
    p2, quads = build.quarter_disc(hc, 0.75)
    parts = [build.extrude("upper", p2, quads, build.LENGTH), build.extrude("lower", p2, quads, build.LENGTH, flip_y=True)]
    out, coords, noff, eoff, nsets, surfs = [], [], 0, 0, {}, {}
    elements = []
    for part in parts:
        coords.append(part.points)
        elements.append((part.name, part.cells + noff + 1, eoff + 1))
        face_of = {}
        for e, cell in enumerate(part.cells):
            for f, loc in FACES.items():
                face_of[frozenset(cell[list(loc)])] = (eoff + e + 1, f)
        for name, faces in part.surfaces.items():
            nsets[name] = np.unique(faces) + noff + 1
            if name.endswith("_arc"):
                surfs[name] = [face_of[frozenset(q)] for q in faces]
        noff += len(part.points)
        eoff += len(part.cells)
    X = np.concatenate(coords)
    out.append("*HEADING\nHertz: two parallel cylinders (quarter models of meshes/hertz/build.py)\n*NODE, NSET=NALL\n")
    # %.12e: ccx reads 20 characters of a field ("-3.99999466669243e-05" lost its last digit)
    out.append("".join(f"{i + 1}, {x:.12e}, {y:.12e}, {z:.12e}\n" for i, (x, y, z) in enumerate(X)))
    for name, cells, first in elements:
        out.append(f"*ELEMENT, TYPE={element}, ELSET={name.upper()}\n")
        out.append("".join(f"{first + e}, " + ", ".join(str(n) for n in c) + "\n" for e, c in enumerate(cells)))
    for name, ids in nsets.items():
        out.append(f"*NSET, NSET={name.upper()}\n" + _lines(ids))
    for name, faces in surfs.items():
        out.append(f"*SURFACE, NAME={name.upper()}, TYPE=ELEMENT\n" + "".join(f"{e}, S{f}\n" for e, f in faces))
    out.append(f"*MATERIAL, NAME=STEEL\n*ELASTIC\n{build.E:g}, {build.NU:g}\n"
               "*SOLID SECTION, ELSET=UPPER, MATERIAL=STEEL\n*SOLID SECTION, ELSET=LOWER, MATERIAL=STEEL\n"
               f"*SURFACE INTERACTION, NAME=SI\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n{penalty:g}\n"
               "*CONTACT PAIR, INTERACTION=SI, TYPE=SURFACE TO SURFACE\nLOWER_ARC, UPPER_ARC\n"
               "*BOUNDARY\nUPPER_SYM, 1, 1\nLOWER_SYM, 1, 1\nUPPER_ENDS, 3, 3\nLOWER_ENDS, 3, 3\nLOWER_FLAT, 2, 2\n"
               f"*STEP\n*STATIC\n{increment:g}, 1., 1e-5, {increment:g}\n"
               f"*BOUNDARY\nUPPER_FLAT, 2, 2, {-delta:g}\n"
               "*NODE PRINT, NSET=UPPER_FLAT, TOTALS=ONLY\nRF\n*NODE PRINT, NSET=LOWER_FLAT, TOTALS=ONLY\nRF\n"
               "*CONTACT FILE\nCSTR\n*END STEP\n")
    with open(path, "w") as f:
        f.write("".join(out))
    return len(X), nsets["lower_arc"], X


def read_frd_contact(path):
    """The last CONTACT block of an ASCII .frd: {node id: (COPEN, CSLIP1, CSLIP2, CPRESS, ...)}."""
    block, cur = None, None
    with open(path) as f:
        for line in f:
            if line.startswith(" -4"):
                cur = {} if line.split()[1] == "CONTACT" else None
            elif line.startswith(" -1") and cur is not None:
                nid = int(line[3:13])
                body = line[13:].rstrip("\n")
                cur[nid] = [float(body[k:k + 12]) for k in range(0, len(body) - 11, 12)]
            elif line.startswith(" -3") and cur is not None:
                block, cur = cur, None
    return block


def read_dat_totals(path, nset):
    """The last 'total force' of nset in the .dat: (fx, fy, fz)."""
    with open(path) as f:
        text = f.read()
    m = re.findall(rf"total force \(fx,fy,fz\) for set {nset.upper()}[^\n]*\n\s*\n?\s*(\S+)\s+(\S+)\s+(\S+)", text)
    return np.array([float(v) for v in m[-1]])


def run(work, hc, element="C3D8I", penalty=3e8, threads=1, delta=build.DELTA, increment=1.0):
    """Writes and solves the model in work; returns dict(hc, dofs, wall, cpu, rss, res, err) as
    bench/hertz_convergence.py's rows (dofs: 3 per node, constrained ones included)."""
    os.makedirs(work, exist_ok=True)
    nn, slave, X = write_inp(os.path.join(work, "hertz.inp"), hc, element, penalty, delta, increment)
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), CCX_NPROC_STIFFNESS=str(threads), CCX_NPROC_EQUATION_SOLVER=str(threads))
    t0 = time.perf_counter()
    with open(os.path.join(work, "ccx.log"), "w") as log:
        p = subprocess.Popen([CCX, "-i", "hertz"], cwd=work, stdout=log, stderr=subprocess.STDOUT, env=env)
        _, status, usage = os.wait4(p.pid, 0)
    wall = time.perf_counter() - t0
    rc = os.waitstatus_to_exitcode(status)
    with open(os.path.join(work, "ccx.log")) as log:
        text = log.read()
    if rc or "*ERROR" in text:
        raise RuntimeError(f"ccx failed (exit {rc}) in {work}:\n{text[-2000:]}")
    fy = read_dat_totals(os.path.join(work, "hertz.dat"), "LOWER_FLAT")[1]
    P = 2 * abs(fy) / build.LENGTH  # the quarter model carries half the load
    cstr = read_frd_contact(os.path.join(work, "hertz.frd"))
    ids = np.array([i for i in slave if abs(X[i - 1, 2]) < 1e-9])
    x = X[ids - 1, 0]
    p = np.array([abs(cstr[i][3]) if i in cstr else 0.0 for i in ids])  # CPRESS (nodes without contact: not listed)
    o = np.argsort(x)
    xs, ps = x[o], p[o]
    res = {"P": P, "b": report.half_width(xs, ps), "b_fit": report.half_width_fit(xs, ps),
           "p_max": ps[0] if xs[0] < 1e-9 else np.interp(0, xs, ps), "points": len(xs), "loaded": int((ps > 0).sum())}
    hb, hp = report.hertz_line(P)
    err = {"b": res["b"] / hb - 1, "b_fit": res["b_fit"] / hb - 1, "p_max": res["p_max"] / hp - 1}
    return dict(hc=hc, element=element, dofs=3 * nn, wall=wall, cpu=usage.ru_utime + usage.ru_stime,
                rss=usage.ru_maxrss / 1024.0, res=res, err=err, iterations=text.count("iteration "))


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outdir")
    ap.add_argument("--hc", type=float, default=0.04)
    ap.add_argument("--element", default="C3D8I")
    ap.add_argument("--penalty", type=float, default=3e8)
    ap.add_argument("--increment", type=float, default=1.0, help="initial (and largest) fraction of the approach per increment; ccx cuts it back when an increment does not converge")
    a = ap.parse_args()
    r = run(a.outdir, a.hc, a.element, a.penalty, increment=a.increment)
    print(f"ccx {version()} {a.element} hc {a.hc}: DOFs {r['dofs']}, P {r['res']['P']:.2f} N/mm, b {r['res']['b']:.5f} "
          f"({r['err']['b']:+.2%}), b fit {r['err']['b_fit']:+.2%}, p_max {r['res']['p_max']:.1f} ({r['err']['p_max']:+.2%}), "
          f"CPU {r['cpu']:.2f} s, wall {r['wall']:.2f} s, RSS {r['rss']:.0f} MiB")
