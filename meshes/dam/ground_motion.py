#!/usr/bin/python3
"""A synthetic horizontal ground acceleration record, reproducible from its seed.

Stationary Gaussian white noise is filtered by the Kanai-Tajimi ground filter (the soil layer as
a damped oscillator: omega_g, zeta_g) and the Clough-Penzien high-pass filter (omega_f, zeta_f:
removes the long-period content that would make the velocity and displacement drift), modulated
by the Jennings-Housner-Tsai envelope ((t/t1)^2 build-up, strong phase to t2, exp(-c (t - t2))
decay), baseline-corrected (a polynomial t^2..t^5 fitted to the displacement is removed through its
second derivative: the record starts from rest and ends near it) and scaled to the peak ground acceleration. Filtering is done in the frequency
domain (numpy FFT of the whole record; the filters' impulse responses die out within 1 s, far
shorter than the record).

  meshes/dam/ground_motion.py [OUT.csv] [--seed 6] [--pga 0.3] [--duration 20] [--dt 0.01]

writes `t, a_g` rows (s, m/s^2) after a commented header with the parameters; the default output
is meshes/dam/ground_motion.csv, the record shipped with the dam scene (regenerate it with no
arguments: the same numbers, to the 7 printed digits).
"""
import argparse
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
G = 9.81
DEFAULTS = dict(seed=6, pga=0.3, duration=20.0, dt=0.01,
                omega_g=5 * np.pi, zeta_g=0.6,      # Kanai-Tajimi: firm ground, 2.5 Hz
                omega_f=0.5 * np.pi, zeta_f=0.6,    # Clough-Penzien high-pass, 0.25 Hz
                t1=2.0, t2=8.0, decay=0.35)         # envelope: build-up, strong phase end, decay rate (1/s)


def envelope(t, t1, t2, decay):
    """Jennings-Housner-Tsai: (t/t1)^2, then 1, then exp(-decay (t - t2))."""
    return np.where(t < t1, (t / t1) ** 2, np.where(t <= t2, 1.0, np.exp(-decay * (t - t2))))


def filters(omega, omega_g, zeta_g, omega_f, zeta_f):
    """Kanai-Tajimi times Clough-Penzien transfer function at circular frequencies omega."""
    kt = (omega_g**2 + 2j * zeta_g * omega_g * omega) / (omega_g**2 - omega**2 + 2j * zeta_g * omega_g * omega)
    cp = omega**2 / (omega_f**2 - omega**2 + 2j * zeta_f * omega_f * omega)
    return kt * cp


def integrate(a, dt):
    """Velocity and displacement by the trapezoidal rule, from rest."""
    v = np.concatenate([[0.0], np.cumsum(0.5 * (a[1:] + a[:-1]) * dt)])
    d = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * dt)])
    return v, d


def record(seed=6, pga=0.3, duration=20.0, dt=0.01, omega_g=5 * np.pi, zeta_g=0.6,
           omega_f=0.5 * np.pi, zeta_f=0.6, t1=2.0, t2=8.0, decay=0.35):
    """Times (s) and ground acceleration (m/s^2), peak |a| = pga g."""
    n = int(round(duration / dt)) + 1
    t = np.arange(n) * dt
    noise = np.random.default_rng(seed).standard_normal(n)
    omega = 2 * np.pi * np.fft.rfftfreq(n, dt)
    a = np.fft.irfft(np.fft.rfft(noise) * filters(omega, omega_g, zeta_g, omega_f, zeta_f), n)
    a *= envelope(t, t1, t2, decay)
    # baseline: the polynomial sum c_k t^k (k = 2..5: starts at rest) fitted to the displacement
    # is removed through its second derivative, which leaves the record starting from rest
    _, d = integrate(a, dt)
    s = t / t[-1]
    c = np.linalg.lstsq(np.stack([s**k for k in range(2, 6)], axis=1), d, rcond=None)[0]
    a -= sum(k * (k - 1) * ck * s ** (k - 2) for k, ck in zip(range(2, 6), c)) / t[-1] ** 2
    a[0] = 0.0  # (the correction's 3e-3 of the peak there): a table held before a shifted record reads 0
    a *= pga * G / np.abs(a).max()
    return t, a


def write(path, **params):
    p = dict(DEFAULTS, **params)
    t, a = record(**p)
    v, d = integrate(a, p["dt"])
    header = [
        "synthetic horizontal ground acceleration (meshes/dam/ground_motion.py)",
        f"Kanai-Tajimi omega_g {p['omega_g']:.6g} rad/s zeta_g {p['zeta_g']:g}; Clough-Penzien omega_f {p['omega_f']:.6g} rad/s zeta_f {p['zeta_f']:g}",
        f"Jennings envelope t1 {p['t1']:g} s t2 {p['t2']:g} s decay {p['decay']:g} 1/s; seed {p['seed']}; PGA {p['pga']:g} g",
        f"dt {p['dt']:g} s, {len(t)} samples; end velocity {v[-1]:.3e} m/s, end displacement {d[-1]:.3e} m (peak {np.abs(d).max():.3e} m)",
    ]
    with open(path, "w") as f:
        f.write("".join(f"# {line}\n" for line in header))
        f.write("t,a_g\n")
        f.write("".join(f"{ti:.2f},{ai:.7e}\n" for ti, ai in zip(t, a)))
    return path


def read(path):
    """(t, a_g) from a record CSV (the commented header and the column names skipped)."""
    with open(path) as f:
        rows = [line.split(",") for line in f if line[:1] not in ("#", "t")]
    data = np.array(rows, dtype=float)
    return data[:, 0], data[:, 1]


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", nargs="?", default=os.path.join(HERE, "ground_motion.csv"))
    ap.add_argument("--seed", type=int, default=DEFAULTS["seed"])
    ap.add_argument("--pga", type=float, default=DEFAULTS["pga"], help="peak ground acceleration in g")
    ap.add_argument("--duration", type=float, default=DEFAULTS["duration"], help="s")
    ap.add_argument("--dt", type=float, default=DEFAULTS["dt"], help="s")
    a = ap.parse_args()
    print(write(a.out, seed=a.seed, pga=a.pga, duration=a.duration, dt=a.dt))
