#!/usr/bin/python3
"""make run: the column under self-weight, static and sudden (Newmark), against theory.

Static: u_z(z) = -rho g (L z - z^2/2) / E (exact at the nodes of linear elements).
Dynamic (undamped, load applied suddenly): the tip oscillates about the static value with
the period of the first mode of a fixed-free bar, T = 4 L / c, c = sqrt(E / rho), and the
total energy T + U - W is conserved by trapezoidal Newmark."""
import os
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "python"))
from mbcontact import meshgen  # noqa: E402
from mbcontact.results import read_csv  # noqa: E402

E, RHO, G, L = 30.0e9, 2500.0, 9.81, 10.0
SOLVER = os.path.join(os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build")), "mbcontact")


def main():
    work = os.path.join(ROOT, "build", "run")
    os.makedirs(work, exist_ok=True)
    meshgen.box(os.path.join(work, "column.msh"), (0, 0, 0), (1, 1, L), n=(2, 2, 40), cell="hex8", volume_name="column")
    with open(os.path.join(HERE, "scene.yaml")) as f:
        open(os.path.join(work, "column.yaml"), "w").write(f.read())
    scene = os.path.join(work, "column.h5")
    subprocess.run([os.path.join(ROOT, "python", "mbcontact-prep"), os.path.join(work, "column.yaml"), "-o", scene], check=True)
    rows = []
    for analysis in ("static", "dynamic"):
        out = os.path.join(work, analysis)
        t0 = time.perf_counter()
        subprocess.run([SOLVER, "-scene", scene, "-mbc_analysis", analysis, "-mbc_output", out], check=True)
        rows.append((analysis, time.perf_counter() - t0, read_csv(out + "_points.csv"), read_csv(out + "_energy.csv") if analysis == "dynamic" else None))

    static_tip, static_mid = -RHO * G * L**2 / (2 * E), -RHO * G * (L * L / 2 - L * L / 8) / E
    period = 4 * L / np.sqrt(E / RHO)
    print("\nmbcontact - concrete column, 10 m, E = 30 GPa, rho = 2500 kg/m3, self-weight (2x2x40 hex8)\n")
    print(f"{'quantity':44s} {'mbcontact':>14s} {'theory':>14s} {'rel. error':>11s}")
    _, ts, p, _ = rows[0]
    for name, got, ref in (("static top u_z [m]", p["top_uz"][-1], static_tip), ("static mid-height u_z [m]", p["middle_uz"][-1], static_mid)):
        print(f"{name:44s} {got:14.6e} {ref:14.6e} {abs(got / ref - 1):11.2e}")
    _, td, p, e = rows[1]
    t, uz = p["t"], p["top_uz"] - static_tip
    i = np.where((uz[:-1] > 0) & (uz[1:] <= 0))[0]
    cross = t[i] + uz[i] * (t[i + 1] - t[i]) / (uz[i] - uz[i + 1])
    measured = np.diff(cross).mean()
    whole = np.floor(t[-1] / measured) * measured  # average over whole periods from t = 0
    mean = np.trapz(np.interp(np.linspace(0, whole, 20001), t, p["top_uz"]), dx=whole / 20000) / whole
    drift = np.abs(e["total"] - e["total"][0]).max() / e["strain"].max()
    print(f"{'sudden load: mean top u_z [m]':44s} {mean:14.6e} {static_tip:14.6e} {abs(mean / static_tip - 1):11.2e}")
    print(f"{'sudden load: period of the tip [s]':44s} {measured:14.6e} {period:14.6e} {abs(measured / period - 1):11.2e}")
    print(f"{'sudden load: peak top u_z [m] (2x static)':44s} {p['top_uz'].min():14.6e} {2 * static_tip:14.6e} {abs(p['top_uz'].min() / (2 * static_tip) - 1):11.2e}")
    print(f"{'energy drift max|H - H0| / max U, 1000 steps':44s} {drift:14.2e} {0.0:14.1f}")
    print(f"\nrun time: static {ts:.2f} s, dynamic (1000 Newmark steps) {td:.2f} s; results in {work}/*.xmf (ParaView)")


if __name__ == "__main__":
    main()
