"""Ground-motion records: reading (PEER NGA .AT2, one- and multi-column tables), baseline
correction, exact integration, response spectra and Rayleigh damping (docs/scene.md, Ground
motion; docs/dam.md). numpy (and scipy for the spectra); never petsc4py.

Every reader raises RecordError naming the file and the line; the prep turns it into its
InputError with the scene's key path.
"""
import math
import re

import numpy as np

G_STANDARD = 9.80665  # m/s^2: the unit "g" of a PEER record in SI


class RecordError(Exception):
    """A record that cannot be read or used; the message names the file (and line)."""


def _read_lines(path):
    try:
        with open(path, encoding="utf-8", errors="strict") as f:
            return f.read().splitlines()
    except OSError as err:
        raise RecordError(f"cannot read {path}: {err.strerror}") from None
    except UnicodeDecodeError:
        raise RecordError(f"{path} is not a text file") from None


def _finite(values, path, what):
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise RecordError(f"{path}: {what} {bad[0] + 1} is not a finite number")


def read_at2(path):
    """A PEER NGA .AT2 file: (dt, accelerations in g). The header is 4 lines: title, event,
    'ACCELERATION TIME SERIES IN UNITS OF G', then 'NPTS= n, DT= dt SEC' (NGA-West2) or
    'n dt NPTS, DT' (the older form); then the values, any number per line. Checked: the units line
    says G, n >= 2, dt > 0, exactly n finite values."""
    lines = _read_lines(path)
    if len(lines) < 5:
        raise RecordError(f"{path}: a PEER .AT2 file has 4 header lines and then the values; "
                          f"this one has {len(lines)} lines")
    if not re.search(r"\bUNITS\s+OF\s+G\b|\(G\)|\bIN\s+G\b", lines[2], re.I):
        raise RecordError(f"{path} line 3: expected the units line of a PEER acceleration record "
                          f"('... IN UNITS OF G'), got {lines[2].strip()!r}: not an acceleration in g")
    head = lines[3]
    m_n = re.search(r"NPTS\s*=\s*([0-9]+)", head, re.I)
    m_dt = re.search(r"DT\s*=\s*([-+0-9.Ee]+)", head, re.I)
    if m_n and m_dt:
        n, dt = int(m_n.group(1)), m_dt.group(1)
    else:  # the older form: two numbers first
        fields = head.replace(",", " ").split()
        try:
            n, dt = int(fields[0]), fields[1]
        except (IndexError, ValueError):
            raise RecordError(f"{path} line 4: expected 'NPTS= n, DT= dt SEC', got {head.strip()!r}") from None
    try:
        dt = float(dt)
    except ValueError:
        raise RecordError(f"{path} line 4: DT {dt!r} is not a number") from None
    if not (math.isfinite(dt) and dt > 0):
        raise RecordError(f"{path} line 4: DT must be > 0, got {dt:g}")
    if n < 2:
        raise RecordError(f"{path} line 4: NPTS must be at least 2, got {n}")
    values = []
    for number, line in enumerate(lines[4:], start=5):
        for field in line.replace(",", " ").split():
            try:
                values.append(float(field))
            except ValueError:
                raise RecordError(f"{path} line {number}: {field!r} is not a number") from None
    a = np.array(values, dtype=float)
    if a.size != n:
        raise RecordError(f"{path}: the header says NPTS = {n} but the file holds {a.size} values")
    _finite(a, path, "value")
    return dt, a


def read_table(path, column=None, dt=None):
    """A text table (comma, semicolon or blank separated; '#' comments, one header line): with
    dt, no time column, every row's `column` (1-based, default 1) at t = i dt; without, column 1
    is t (strictly increasing) and `column` (default 2) the value. Returns (t, values)."""
    lines = _read_lines(path)
    rows, header_seen, numbers = [], False, []
    for number, line in enumerate(lines, start=1):
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        fields = re.split(r"[,;\s]+", text.strip(",; "))
        try:
            values = [float(v) for v in fields]
        except ValueError:
            if not rows and not header_seen:
                header_seen = True
                continue
            raise RecordError(f"{path} line {number}: expected numbers, got {text!r}") from None
        rows.append(values)
        numbers.append(number)
    if not rows:
        raise RecordError(f"{path} holds no rows of numbers")
    col = (1 if dt is not None else 2) if column is None else column
    if col < 1:
        raise RecordError(f"{path}: column {col}: columns count from 1")
    for values, number in zip(rows, numbers):
        if len(values) < col:
            raise RecordError(f"{path} line {number}: has {len(values)} columns, the record is column {col}")
    f = np.array([r[col - 1] for r in rows])
    _finite(f, path, "row")
    if dt is not None:
        if not (math.isfinite(dt) and dt > 0):
            raise RecordError(f"{path}: dt must be > 0, got {dt:g}")
        t = dt * np.arange(len(f))
    else:
        if col == 1:
            raise RecordError(f"{path}: column 1 is the time; give the record's column (>= 2), or dt for a file without times")
        t = np.array([r[0] for r in rows])
        _finite(t, path, "row")
        bad = np.flatnonzero(np.diff(t) <= 0)
        if bad.size:
            raise RecordError(f"{path} line {numbers[bad[0] + 1]}: t must be strictly increasing "
                              f"(t={t[bad[0] + 1]:g} follows t={t[bad[0]]:g})")
    if len(f) < 2:
        raise RecordError(f"{path}: a record needs at least 2 rows, got {len(f)}")
    return t, f


BASELINES = {"none": -1, "constant": 0, "linear": 1, "quadratic": 2, "cubic": 3}


def integrate(t, a):
    """Velocity and displacement of a piecewise-linear acceleration, from rest at t[0]: exact at
    the rows (v: trapezoid; d: the cubic's integral, h^2 (a_i / 3 + a_i+1 / 6))."""
    h = np.diff(t)
    v = np.concatenate([[0.0], np.cumsum(h * (a[:-1] + a[1:]) / 2)])
    d = np.concatenate([[0.0], np.cumsum(h * v[:-1] + h * h * (a[:-1] / 3 + a[1:] / 6))])
    return v, d


def baseline_correct(t, a, order):
    """Removes from a the second derivative of the polynomial c_2 s^2 + ... + c_(order+2)
    s^(order+2) (s = t - t0) fitted by least squares to the record's displacement: the
    acceleration's correction is a polynomial of degree `order` (0: constant, 1: linear, ...)
    and the record still starts at rest. The usual correction of a processed record's drift."""
    if order < 0:
        return a
    s = t - t[0]
    _, d = integrate(t, a)
    powers = np.arange(2, order + 3)
    scale = s[-1] if s[-1] > 0 else 1.0
    A = (s[:, None] / scale) ** powers[None, :]
    c, *_ = np.linalg.lstsq(A, d, rcond=None)
    corr = sum(ci * p * (p - 1) * (s / scale) ** (p - 2) / scale ** 2 for ci, p in zip(c, powers))
    return a - corr


def padded(t, a):
    """The record with a zero row one step before its first and after its last row where those
    values are not 0: the scene's tables hold their end values outside, a record is 0 there."""
    if a[0] != 0:
        t, a = np.concatenate([[t[0] - (t[1] - t[0])], t]), np.concatenate([[0.0], a])
    if a[-1] != 0:
        t, a = np.concatenate([t, [t[-1] + (t[-1] - t[-2])]]), np.concatenate([a, [0.0]])
    return t, a


def response_spectrum(t, a, periods, damping=0.05):
    """Response spectrum of a ground acceleration a(t) (piecewise linear between the samples, any
    step): for each period T, the peak relative displacement SD, pseudo-velocity PSV = w SD,
    pseudo-acceleration PSA = w^2 SD and peak absolute acceleration SA of the linear oscillator
    x'' + 2 z w x' + w^2 x = -a, by the exact recurrence of Nigam and Jennings (1969) for a
    piecewise-linear load: no error from the step itself. Returns a dict of arrays."""
    t = np.asarray(t, float)
    a = np.asarray(a, float)
    periods = np.atleast_1d(np.asarray(periods, float))
    if np.any(periods <= 0):
        raise ValueError("periods must be > 0")
    if not 0 <= damping < 1:
        raise ValueError("damping must lie in [0, 1)")
    out = {k: np.zeros(len(periods)) for k in ("SD", "PSV", "PSA", "SA")}
    h = np.diff(t)
    for k, T in enumerate(periods):
        w = 2 * np.pi / T
        x, v, sd, sa = 0.0, 0.0, 0.0, 0.0
        cache = {}
        for i in range(len(h)):
            dt = h[i]
            key = round(dt, 15)
            if key not in cache:
                cache[key] = _nigam_jennings(w, damping, dt)
            A, B = cache[key]
            p0, p1 = -a[i], -a[i + 1]
            x, v = (A[0, 0] * x + A[0, 1] * v + B[0, 0] * p0 + B[0, 1] * p1,
                    A[1, 0] * x + A[1, 1] * v + B[1, 0] * p0 + B[1, 1] * p1)
            sd = max(sd, abs(x))
            sa = max(sa, abs(-2 * damping * w * v - w * w * x))  # x'' + a = absolute acceleration
        out["SD"][k], out["SA"][k] = sd, sa
        out["PSV"][k], out["PSA"][k] = w * sd, w * w * sd
    out["T"] = periods
    return out


def _nigam_jennings(w, z, dt):
    """Matrices A, B with [x, v]_(i+1) = A [x, v]_i + B [p_i, p_(i+1)] for x'' + 2 z w x' + w^2 x
    = p(t), p linear over the step: the exact solution (Nigam and Jennings 1969), here as the
    exponential of the system augmented by p and its slope."""
    from scipy.linalg import expm

    F = np.array([[0.0, 1.0, 0.0, 0.0], [-w * w, -2 * z * w, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]])
    E = expm(F * dt)
    A = E[:2, :2]
    B = np.column_stack([E[:2, 2] - E[:2, 3] / dt, E[:2, 3] / dt])
    return A, B


def rayleigh(f1, f2, damping=0.05, damping2=None):
    """Rayleigh coefficients (alpha, beta) of C = alpha M + beta K with the damping ratios
    `damping` at frequency f1 and `damping2` (default the same) at f2 (Hz):
    z(w) = alpha / (2 w) + beta w / 2 at w1 = 2 pi f1 and w2 = 2 pi f2."""
    z1, z2 = damping, damping if damping2 is None else damping2
    if not (f1 > 0 and f2 > 0 and f1 != f2):
        raise ValueError(f"rayleigh: two different positive frequencies needed, got {f1}, {f2}")
    w1, w2 = 2 * np.pi * f1, 2 * np.pi * f2
    beta = 2 * (z2 * w2 - z1 * w1) / (w2 * w2 - w1 * w1)
    alpha = 2 * z1 * w1 - beta * w1 * w1
    return alpha, beta
