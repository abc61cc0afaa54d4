#!/usr/bin/python3
"""A concrete gravity dam of several monoliths on a rock foundation (docs/dam.md).

Axes: x downstream (the upstream face is x = 0), y along the dam axis, z up (the foundation's top
is z = 0). Every monolith is a body with a gravity-dam cross-section: vertical upstream face,
crest of width `crest`, downstream face of slope `slope` (H:V) from the knee down to the toe,
base width B = crest + slope z_knee (z_knee = H - crest / slope). Neighbouring monoliths touch at
contraction joints (couples 2, 3, ..., friction `mu_joint`); the monoliths' bases rest on the
foundation block (couple 1, friction `mu_base`); in dynamic and staged analyses every couple slides
small (`sliding`: the pairs fixed per stage, docs/dam.md). The foundation extends `upstream` H upstream,
`downstream` H downstream, `abutment` H beyond the end monoliths and `depth` H down, graded away
from the dam; its bottom is fixed, its sides on rollers (`sides`). Loads: the monoliths'
self-weight (the foundation's own weight is its in-situ state and is left out), the reservoir's
hydrostatic pressure on the upstream faces and on the reservoir floor (level `level`), and in a
dynamic analysis a horizontal ground acceleration record along x in the relative-motion form
(body force -density a_g(t) on every body; meshes/dam/ground_motion.csv, made by
ground_motion.py), after the static loads are ramped.

Meshes are structured hex8, one vertex set per body (like meshgen.boxes), vectorised numpy. The
interfaces do not match on purpose (layout()): the monoliths' base faces are the master side
(their nodes carry the contact points) over a finer foundation surface that reaches beyond the
footprint; at a joint the odd (coarser) monolith is the master, its border rows left out so
every master node lies inside the slave face. Size: element size `h`, or `target_dofs` (a few
thousand to millions).

  meshes/dam/build.py OUTDIR [--h 5 | --dofs 1e6] [--monoliths 4] [--mu-base 0.8] [--mu-joint 0.8]
                      [--level 95] [--dynamic [--eq-duration 20] | --quasi-static | --staged | --modal] [--[no-]joints]
                      [--added-mass] [--foundation massed|massless|radiating] [--components x|xy|xyz]
                      [--at2 X.AT2 [Y.AT2 [Z.AT2]]] [--sliding small|finite] [--binary] [--lift-joints N | --lift-heights Z ...]
                      [--uplift [--tail-water 0] [--drains 0.05] [--drain-efficiency 0.5] [--no-penetration]]
                      [--cohesion-base C [--tensile-base T]] [--cohesion-lift C [--tensile-lift T]] [--mu-residual M] [--softening D]

writes dam.msh, dam.yaml, dam.json (parameters, W, T for report.py), ground_motion.csv when
dynamic, and dam.h5 (mbcontact-prep); then
  build/mbcontact -scene OUTDIR/dam.h5 && meshes/dam/report.py OUTDIR/dam_result
"""
import argparse
import json
import os
import shutil
import sys
import time
from dataclasses import asdict, dataclass, replace

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "python"))
from mbcontact import meshgen  # noqa: E402
from mbcontact.cells import min_corner_volume  # noqa: E402
from mbcontact.prep import prepare  # noqa: E402

G = 9.81
WATER = 9810.0  # unit weight of water, N/m3
RECORD = os.path.join(HERE, "ground_motion.csv")


@dataclass
class Dam:
    """Parameters (SI units). Lengths in m; upstream, downstream, depth in units of the height."""
    monoliths: int = 4
    height: float = 100.0
    crest: float = 8.0
    slope: float = 0.78           # downstream face, horizontal : vertical
    width: float = 20.0           # of a monolith along the dam axis (joint spacing)
    upstream: float = 1.0         # foundation extent upstream of the heel / height
    downstream: float = 1.5       # downstream of the toe / height
    depth: float = 1.0            # / height
    abutment: float = 0.25        # beyond each end monolith along the axis / height
    h: float = 5.0                # element size in the dam and under it
    growth: float = 1.3           # foundation grading away from the dam
    hmax: float = 0.0             # largest foundation element (0: 4 h)
    level: float = 0.0            # reservoir level above the base (0: 0.95 height)
    mu_base: float = 0.8
    mu_joint: float = 0.8
    ring: int = 2                 # foundation contact surface: elements beyond the dam's footprint
    joints: bool = None           # contraction joints as contact couples (default: dynamic only, docs/dam.md)
    joint_base_rows: int = 1      # element rows above the base left out of the joint surfaces (see monolith())
    sliding: str = None           # the couples' sliding: small | finite (default: small in dynamic and staged analyses, docs/dam.md)
    sides: str = "normal"         # foundation sides: normal (rollers) | all | none
    floor: bool = True            # hydrostatic pressure on the reservoir floor too
    E: float = 25e9               # concrete
    nu: float = 0.2
    density: float = 2400.0
    rock_E: float = 20e9
    rock_nu: float = 0.25
    rock_density: float = 2700.0  # used by dynamic analyses only (no rock self-weight)
    added_mass: bool = False      # the reservoir's Westergaard added mass on the upstream faces (dynamic, modal)
    foundation_model: str = "massed"  # massed (its inertia, base fixed) | massless | radiating (absorbing sides and base, the record entering as the outcrop motion)
    components: str = "x"         # the ground motion's components: x | xy | xyz (y: another synthetic record, z: 2/3 of a third)
    at2: tuple = ()               # PEER .AT2 records for x (and y, z) instead of the synthetic ones
    lift_joints: tuple = ()       # heights of horizontal lift joints through every monolith (m), each a couple
    uplift: bool = False          # the water pressure under the base and in the lift joints (docs/dam.md, Uplift)
    tail_water: float = 0.0       # head at the toe (m above the base)
    drains: float = 0.05          # the drain line's distance from the heel / the joint's length (0: no drains)
    drain_efficiency: float = 0.5 # USACE / FERC: at most 0.5 without measurements
    penetration: bool = True      # the reservoir's water enters a joint where it opens (with uplift)
    cohesion_base: float = 0.0    # the base's joint law (docs/dam.md, Bonded joints): cohesion (Pa; 0: unbonded)
    tensile_base: float = None    #   its tensile strength (None: cohesion / mu_base)
    cohesion_lift: float = 0.0    # the lift joints' cohesion (Pa; 0: unbonded)
    tensile_lift: float = None    #   their tensile strength (None: cohesion / mu_joint)
    mu_residual: float = None     # friction once a bond broke (None: the joint's mu)
    softening: float = 0.0        # the bonds' softening displacement (m; 0: brittle)
    static_steps: int = 0         # static load steps (0: 1, or 12 with uplift's penetration: the water raised over the first half, then held while the wet length settles)

    @property
    def z_knee(self):
        return self.height - self.crest / self.slope

    @property
    def base(self):
        return self.crest + self.slope * self.z_knee

    @property
    def water(self):
        return self.level if self.level > 0 else 0.95 * self.height

    def section_area(self):
        return self.crest * self.height + 0.5 * (self.base - self.crest) * self.z_knee

    def weight(self):
        """Self-weight of one monolith, N."""
        return self.density * G * self.section_area() * self.width

    def thrust(self):
        """Hydrostatic thrust on one monolith's upstream face, N."""
        return WATER * min(self.water, self.height) ** 2 / 2 * self.width

    def check(self):
        if self.monoliths < 1 or self.height <= 0 or self.width <= 0 or self.h <= 0:
            raise ValueError("monoliths >= 1, height, width and h > 0 needed")
        if not (0 < self.crest and 0 < self.slope and self.z_knee > 0):
            raise ValueError(f"crest {self.crest} and slope {self.slope}: the downstream face must start below "
                             f"the crest (crest / slope < height)")
        if self.sides not in ("normal", "all", "none"):
            raise ValueError(f"sides must be normal, all or none, got {self.sides!r}")
        if self.foundation_model not in ("massed", "massless", "radiating"):
            raise ValueError(f"foundation_model must be massed, massless or radiating, got {self.foundation_model!r}")
        if self.components not in ("x", "xy", "xyz"):
            raise ValueError(f"components must be x, xy or xyz, got {self.components!r}")
        if len(self.at2) > 3:
            raise ValueError("at most three .AT2 records (x, y, z)")
        lifts = sorted(self.lift_joints)
        if any(not 0 < z < self.height for z in lifts) or len(set(lifts)) < len(lifts):
            raise ValueError(f"lift joints at {list(self.lift_joints)}: distinct heights strictly between the base and "
                             f"the crest (0 < z < {self.height:g}) needed")
        if not 0 <= self.drains < 1 or not 0 <= self.drain_efficiency <= 1:
            raise ValueError(f"drains {self.drains:g} (a fraction of the joint's length, < 1) and drain efficiency "
                             f"{self.drain_efficiency:g} (in [0, 1]) needed")
        if self.uplift and not 0 <= self.tail_water <= self.water:
            raise ValueError(f"tail water {self.tail_water:g} m must lie between the base and the reservoir ({self.water:g} m)")
        return self

    def load_steps(self):
        """The static analysis's (or the staged analysis's static stage's) load steps: 12 with water
        entering the joints (the reservoir raised over the first 6, then held), else 1."""
        return self.static_steps or (12 if self.uplift and self.penetration else 1)

    def lifts(self):
        """The lift joints' heights, ascending."""
        return sorted(float(z) for z in self.lift_joints)

    def section_width(self, z):
        """The cross-section's width (heel to downstream face) at height z."""
        return self.crest + self.slope * (self.z_knee - z) if z <= self.z_knee else self.crest


def graded(h0, length, growth, hmax):
    """Node offsets 0 .. length: steps h0, h0 growth, ... capped at hmax; the steps are scaled
    (by less than half a step overall) so the last node lands on length."""
    steps, total = [], 0.0
    while total < length - 1e-9 * length:
        steps.append(min(h0 * growth ** len(steps), hmax))
        total += steps[-1]
    if len(steps) > 1 and total - length > 0.5 * steps[-1]:
        total -= steps.pop()
    return np.concatenate([[0.0], np.cumsum(steps) * length / total])


def divisions(length, h):
    return max(1, int(round(length / h)))


def layout(p):
    """The mesh axes. The interfaces do not match: odd monoliths have nx x ny x nz elements, even
    ones one more along x and z (a joint pairs a coarser master with a finer slave), and the
    foundation under the dam is finer than both, with no node on a joint line. A master node
    then projects into a slave face rather than onto a vertex shared by four, whose choice
    flips with rounding from step to step and makes the solver rebuild D."""
    hmax = p.hmax or 4 * p.h
    nz1, nz2 = divisions(p.z_knee, p.h), divisions(p.height - p.z_knee, p.h)
    nx, ny = max(2, divisions(p.base, p.h)), divisions(p.width, p.h)
    # z levels: the knee and the lift joints are levels of every monolith (a lift joint is a plane)
    breaks = sorted({0.0, p.z_knee, p.height, *p.lifts()})
    mono = []
    for k in range(1, p.monoliths + 1):
        r = 1 - k % 2  # 0 for odd monoliths (masters of their joints), 1 for even ones
        z = [0.0]
        for i, (z0, z1) in enumerate(zip(breaks[:-1], breaks[1:])):
            z += list(np.linspace(z0, z1, divisions(z1 - z0, p.h) + (r if i == 0 else 0) + 1)[1:])
        z = np.array(z)
        lifts = [0] + [int(np.argmin(np.abs(z - zl))) for zl in p.lifts()] + [len(z) - 1]
        mono.append(dict(nx=nx + r, ny=ny, z=z, lifts=lifts))
    nfx = nx + 2
    dx = p.base / nfx
    up = graded(dx, p.upstream * p.height, p.growth, hmax)
    down = graded(dx, p.downstream * p.height, p.growth, hmax)
    fx = np.concatenate([-up[::-1], np.linspace(0, p.base, nfx + 1)[1:], p.base + down[1:]])
    span, m = p.monoliths * p.width, p.monoliths * (ny + 1) - 1
    ends = graded(span / m, p.abutment * p.height, p.growth, hmax) if p.abutment > 0 else np.zeros(1)
    fy = np.concatenate([-ends[::-1], np.linspace(0, span, m + 1)[1:], span + ends[1:]])
    fz = -graded(mono[0]["z"][1], p.depth * p.height, p.growth, hmax)[::-1]
    return dict(mono=mono, nx=nx, ny=ny, nz=nz1 + nz2, fx=fx, fy=fy, fz=fz)


def count_dofs(p):
    a = layout(p)
    dams = sum((m["nx"] + 1) * (m["ny"] + 1) * len(m["z"]) for m in a["mono"])
    return 3 * (dams + len(a["fx"]) * len(a["fy"]) * len(a["fz"]))


def size_for_dofs(p, target):
    """The element size whose mesh has the DOF count nearest to target (bisection on log h)."""
    lo, hi = np.log(p.height / 2000), np.log(p.height)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if count_dofs(replace(p, h=np.exp(mid))) > target:
            lo = mid
        else:
            hi = mid
    candidates = [np.exp(lo), np.exp(hi)]
    return min(candidates, key=lambda h: abs(count_dofs(replace(p, h=h)) - target))


def _lattice(n):
    """Integer lattice [0, n] as points (i fastest), hex8 cells and outward boundary faces per side."""
    return meshgen._box_arrays((0, 0, 0), tuple(n), tuple(n), "hex8", 0.0, 0)


def lift_name(k, j):
    """Body name of lift j (0: the lowest, on the base) of monolith k."""
    return f"m{k}" if j == 0 else f"m{k}_l{j}"


def monolith(p, a, k):
    """Points, cells and surfaces of monolith k (1-based), a scene without lift joints (one body)."""
    parts = monolith_lifts(p, a, k)
    if len(parts) != 1:
        raise ValueError(f"monolith m{k} has {len(parts)} lifts: take monolith_lifts()")
    return parts[0][1:]


def monolith_lifts(p, a, k):
    """The lifts of monolith k (1-based): (name, points, cells, surfaces) each, one lift (the whole
    monolith, body m<k>) without lift joints; x = x_d(z) i / nx on every z level. Lift j has one
    element more along x and y than the lifts next to it (j odd): a lift joint's meshes do not
    match, for the reason the base's and the contraction joints' do not (layout())."""
    m = a["mono"][k - 1]
    nzk = len(m["z"]) - 1
    lifts = m["lifts"]
    rows = max(p.joint_base_rows, 0)
    parts = []
    for li, (lo, hi) in enumerate(zip(lifts[:-1], lifts[1:])):
        nx, ny = m["nx"] + li % 2, m["ny"] + li % 2
        ref, cells, sides = _lattice((nx, ny, hi - lo))
        i, j, kz = ref[:, 0], ref[:, 1], ref[:, 2].astype(int) + lo
        z = m["z"][kz]
        xd = np.where(z <= p.z_knee, p.crest + p.slope * (p.z_knee - z), p.crest)
        points = np.stack([xd * i / nx, (k - 1) * p.width + j * p.width / ny, z], axis=1)
        # Joint surfaces. The faces of the lowest rows are left out: a base node on a joint would
        # carry a point of the base couple and one of the joint, and with the neighbour's base
        # point the three constraints are linearly dependent (A_y - F_y, A_y - A'_y, A'_y - F_y for
        # a foundation face F under both), which stalls the multiplier solve; so are the rows
        # touching a lift joint, for the same reason. On the master side (odd monoliths) the faces
        # along the upstream, downstream and crest edges are left out too, so every master node
        # lies inside the slave surface: a node on its border enters and leaves it with
        # rounding-level motions, changing the contact pairs (and rebuilding D) every step.
        joint = {}
        for side in ("ymin", "ymax"):
            f = sides[side]
            zlo, zhi = ref[f][:, :, 2].min(axis=1) + lo, ref[f][:, :, 2].max(axis=1) + lo
            keep = zlo >= rows
            for level in lifts[1:-1]:
                keep &= ~((zlo <= level) & (zhi >= level))
            if k % 2:
                keep &= (ref[f][:, :, 0].min(axis=1) > 0) & (ref[f][:, :, 0].max(axis=1) < nx) & (zhi < nzk)
            joint[side] = f[keep]
        surf = {f"m{k}_ymin": joint["ymin"], f"m{k}_ymax": joint["ymax"], "upstream": sides["xmin"]}
        if li == 0:
            surf[f"m{k}_base"] = sides["zmin"]
        else:  # the lift's bottom: the master of lift joint li
            surf[f"m{k}_lift{li}_upper"] = sides["zmin"]
        if li + 1 < len(lifts) - 1:  # its top: the slave of lift joint li + 1
            surf[f"m{k}_lift{li + 1}_lower"] = sides["zmax"]
        parts.append((lift_name(k, li), points, cells, surf))
    for side in ("ymin", "ymax"):
        used = p.joints and k % 2 and (k < p.monoliths if side == "ymax" else k > 1)
        if used and not sum(len(part[3][f"m{k}_{side}"]) for part in parts):
            raise ValueError(f"h = {p.h:g} m is too coarse for joints: monolith m{k} has {m['nx']} x {nzk} elements on its "
                             f"joint and keeps no face inside its upstream, downstream, crest and lift edges for the joint's "
                             "master side; take a smaller h (more DOFs)")
    return parts


def _footprint(p, a, cx, cy):
    """Whether the foundation's top faces with centres (cx, cy) lie under the dam with `ring`
    elements beyond it on every side (the contact surface)."""
    def beyond(axis, lo, hi):  # coordinates `ring` elements outside [lo, hi]
        i, j = np.searchsorted(axis, lo - 1e-9 * abs(hi - lo)), np.searchsorted(axis, hi - 1e-9 * abs(hi - lo))
        return axis[max(i - p.ring, 0)], axis[min(j + p.ring, len(axis) - 1)]

    x0, x1 = beyond(a["fx"], 0.0, p.base)
    y0, y1 = beyond(a["fy"], 0.0, p.monoliths * p.width)
    return (cx > x0) & (cx < x1) & (cy > y0) & (cy < y1)


def wet_surfaces(p, a):
    """The foundation's top surfaces the reservoir loads: the floor upstream of the contact ring and
    the ring's upstream part (heel_ring), those that have faces (a foundation that ends within the
    ring upstream has no floor: a load on it would name a surface the mesh does not have)."""
    cx, cy = np.meshgrid(0.5 * (a["fx"][1:] + a["fx"][:-1]), 0.5 * (a["fy"][1:] + a["fy"][:-1]), indexing="ij")
    footprint = _footprint(p, a, cx, cy)
    faces = {"floor": ~footprint & (cx < 0), "heel_ring": footprint & (cx < 0)}
    return [name for name in ("floor", "heel_ring") if faces[name].any()]


def foundation(p, a):
    """Points, cells and surfaces of the foundation block. Its top: the contact surface under the
    dam with `ring` elements beyond the footprint on every side (a base node moved off the
    footprint by a micrometre would lose its contact point), split into the wet part upstream of
    the heel (heel_ring: also loaded by the water) and the dry rest (foundation_contact), the
    reservoir floor upstream (floor) and the dry rest downstream (not a surface)."""
    fx, fy, fz = a["fx"], a["fy"], a["fz"]
    ref, cells, sides = _lattice((len(fx) - 1, len(fy) - 1, len(fz) - 1))
    idx = ref.astype(int)
    points = np.stack([fx[idx[:, 0]], fy[idx[:, 1]], fz[idx[:, 2]]], axis=1)
    top = sides["zmax"]
    cx, cy = points[top][:, :, 0].mean(axis=1), points[top][:, :, 1].mean(axis=1)
    footprint = _footprint(p, a, cx, cy)
    surfaces = {"foundation_contact": top[footprint & (cx > 0)], "heel_ring": top[footprint & (cx < 0)],
                "floor": top[~footprint & (cx < 0)], "foundation_bottom": sides["zmin"],
                "foundation_xsides": np.concatenate([sides["xmin"], sides["xmax"]]),
                "foundation_ysides": np.concatenate([sides["ymin"], sides["ymax"]])}
    return points, cells, surfaces


def write_mesh(path, p, a, binary=False):
    """All bodies into one Gmsh 2.2 file, each with its own vertices; a surface name used by
    several bodies (upstream) is one region."""
    parts = [part for k in range(1, p.monoliths + 1) for part in monolith_lifts(p, a, k)] + [("foundation", *foundation(p, a))]
    points, regions, surfaces, offset = [], [], {}, 0
    for name, pts, cells, surf in parts:
        bad = np.count_nonzero(min_corner_volume("hex8", pts, cells) <= 0)
        if bad:
            raise ValueError(f"{name}: {bad} inverted or flat hex8 cells (crest {p.crest}, slope {p.slope}, h {p.h})")
        points.append(pts)
        regions.append((name, 3, "hexahedron", cells + offset))
        for sname, faces in surf.items():
            surfaces.setdefault(sname, []).append(faces + offset)
        offset += len(pts)
    regions += [(name, 2, "quad", np.concatenate(faces)) for name, faces in surfaces.items()]
    meshgen._write_gmsh(path, np.concatenate(points), regions, binary=binary)
    return offset


def couple_names(p):
    """{k: name} of the scene's couples: 1 the base, 1 + k the joint between monoliths k and k + 1,
    then the lift joints from the lowest (k = lift_k(p, j))."""
    names = {1: "base"}
    if p.joints:
        names.update({1 + k: f"joint m{k}|m{k + 1}" for k in range(1, p.monoliths)})
    names.update({lift_k(p, j): f"lift {j} (z = {z:g})" for j, z in enumerate(p.lifts(), start=1)})
    return names


def lift_k(p, j):
    """The couple number of lift joint j (1: the lowest)."""
    return p.monoliths + j


def uplift(p, z, length):
    """The uplift keys of a joint at height z of the given length (heel to toe): USACE / FERC's
    heel-to-toe law, the reservoir's head at the heel, the tail water's at the toe (none above it),
    the drain line at `drains` of the length; the water entering where the joint opens."""
    heel = max(p.water - z, 0.0)
    up = {"origin": [0.0, 0.0, z], "direction": [1.0, 0.0, 0.0], "length": length, "heel_head": heel,
          "tail_head": min(max(p.tail_water - z, 0.0), heel), "unit_weight": WATER, "level": p.water,
          "penetration": p.penetration}
    if p.drains > 0:
        up.update(drain=p.drains * length, drain_efficiency=p.drain_efficiency)
    return up


def rayleigh(p, zeta=0.05, ratio=5.0):
    """alpha, beta of C = alpha M + beta K giving zeta at the dam's first frequency (Fenves and
    Chopra's estimate T1 = 1.4 H / sqrt(E) with H in ft and E in psi) and at ratio times it."""
    t1 = 1.4 * (p.height / 0.3048) / np.sqrt(p.E / 6894.757)
    w1 = 2 * np.pi / t1
    w2 = ratio * w1
    return float(2 * zeta * w1 * w2 / (w1 + w2)), float(2 * zeta / (w1 + w2))


def ground_motion(p, record, shift):
    """The ground_acceleration load: the record along x (a CSV in m/s^2 or a PEER .AT2 in g), and
    along y and z with `components` (record_y, record_z beside it)."""
    load = {"kind": "ground_acceleration", "shift": shift}
    for i, c in enumerate(p.components):
        name = record if c == "x" else record.replace(".csv", f"_{c}.csv")
        if i < len(p.at2):
            load[c] = {"at2": os.path.basename(p.at2[i]), "g": G}
        else:
            load[c] = {"csv": name}
    return load


def scene(p, analysis="static", dt=0.01, ramp=1.0, eq_start=2.0, eq_duration=20.0, record="ground_motion.csv",
          every=10):
    """The scene dict. Static: self-weight and water at once, one step, the monoliths held by
    contact (static stabilisation). Dynamic: self-weight and water ramped over `ramp` s (bodies
    held only by contact cannot take `constant` loads: docs/scene.md), the record from eq_start.
    Staged: a static stage (self-weight and water, one step to t = 1), then a dynamic stage from
    that state with the record from its start (t = 1) for eq_duration s."""
    staged = analysis == "staged"
    seismic = analysis in ("dynamic", "staged")
    radiating = seismic and p.foundation_model == "radiating"
    if radiating and not staged:
        raise ValueError("a radiating foundation needs the staged analysis (its absorbing boundaries hold it in the "
                         "static stage; a ramp would push it into its dashpots)")
    n = p.monoliths
    dams = [lift_name(k, j) for k in range(1, n + 1) for j in range(len(p.lifts()) + 1)]
    concrete = {"E": p.E, "nu": p.nu, "density": p.density}
    rock = {"E": p.rock_E, "nu": p.rock_nu}
    if seismic:
        alpha, beta = rayleigh(p)
        if radiating:  # absolute motion: a mass-proportional term would damp the rigid ground motion itself
            alpha, beta = 0.0, rayleigh(p, ratio=1.0)[1] * 2
        concrete.update(rayleigh_alpha=alpha, rayleigh_beta=beta)
        rock.update(density=p.rock_density, rayleigh_alpha=alpha, rayleigh_beta=beta)
    if analysis == "modal":
        rock.update(density=p.rock_density)
    bodies = {d: {"mesh": "m", "regions": d, "material": dict(concrete)} for d in dams}
    bodies["foundation"] = {"mesh": "m", "regions": "foundation", "material": rock}
    if p.foundation_model == "massless" and analysis != "static":  # the classical approach: inertia in the dam only
        rock.update(density=0.0, rayleigh_alpha=0.0)
        bodies["foundation"]["massless"] = True
    couples = [{"k": 1, "master": [f"m{k}_base" for k in range(1, n + 1)], "slave": ["foundation_contact", "heel_ring"],
                "mu": p.mu_base}]
    if p.joints:  # joint k between monoliths k and k + 1: the odd (coarser) one is the master
        couples += [{"k": 1 + k, "master": f"m{k}_ymax" if k % 2 else f"m{k + 1}_ymin",
                     "slave": f"m{k + 1}_ymin" if k % 2 else f"m{k}_ymax", "mu": p.mu_joint} for k in range(1, n)]
    for j, z in enumerate(p.lifts(), start=1):  # lift joint j: every monolith's lift above it on the one below
        couples.append({"k": lift_k(p, j), "master": [f"m{k}_lift{j}_upper" for k in range(1, n + 1)],
                        "slave": [f"m{k}_lift{j}_lower" for k in range(1, n + 1)], "mu": p.mu_joint})
    for c in couples:
        c["sliding"] = p.sliding
    for c, coh, ft in [(couples[0], p.cohesion_base, p.tensile_base)] + \
            [(next(c for c in couples if c["k"] == lift_k(p, j)), p.cohesion_lift, p.tensile_lift) for j in range(1, len(p.lifts()) + 1)]:
        if coh > 0:  # a bonded joint (docs/dam.md, Bonded joints)
            c["cohesion"] = coh
            c.update({k: v for k, v in (("tensile_strength", ft), ("mu_residual", p.mu_residual)) if v is not None})
            if p.softening > 0:
                c["softening_displacement"] = p.softening
    steps = p.load_steps() if analysis in ("static", "staged") else 1  # the static analysis's or stage's
    # A static analysis with water entering the joints raises the reservoir over the first half of its
    # load steps and holds it: the crack and the water in it grow together (at the full load at once
    # the first step's dry crack floods in one jump, which the multiplier solve may not follow)
    water = {"table": [[0, 0], [steps // 2, 1]]} if steps > 1 and p.uplift and p.penetration else "constant"
    if p.uplift:
        ramped_up = {"table": [[0, 0], [ramp, 1]]} if analysis == "dynamic" else water
        couples[0]["uplift"] = dict(uplift(p, 0.0, p.base), time=ramped_up)
        for j, z in enumerate(p.lifts(), start=1):
            if p.water > z:  # a joint above the reservoir has none
                next(c for c in couples if c["k"] == lift_k(p, j))["uplift"] = dict(uplift(p, z, p.section_width(z)), time=ramped_up)
    dirichlet = [{"surface": "foundation_bottom", "components": "all"}]
    if p.sides == "normal":
        dirichlet += [{"surface": "foundation_xsides", "components": ["x"]}, {"surface": "foundation_ysides", "components": ["y"]}]
    elif p.sides == "all":
        dirichlet += [{"surface": "foundation_xsides"}, {"surface": "foundation_ysides"}]
    absorbing = []
    if radiating:  # Lysmer-Kuhlemeyer dashpots instead of the supports, the record coming in at the bottom
        dirichlet = []
        absorbing = [{"surface": "foundation_bottom", "input": "outcrop"},
                     {"surface": "foundation_xsides"}, {"surface": "foundation_ysides"}]
    ramped = {"table": [[0, 0], [ramp, 1]]} if analysis == "dynamic" else "constant"
    water = ramped if analysis == "dynamic" else water
    loads = [{"kind": "gravity", "vector": [0, 0, -G], "bodies": dams, "time": ramped},
             {"kind": "hydrostatic", "surface": "upstream", "level": p.water, "unit_weight": WATER, "time": water}]
    if p.floor:
        loads += [{"kind": "hydrostatic", "surface": name, "level": p.water, "unit_weight": WATER, "time": water}
                  for name in wet_surfaces(p, layout(p))]
    mid = [(k - 0.5) * p.width for k in range(1, n + 1)]
    points = {}
    for k, y in enumerate(mid, start=1):
        points[f"crest_m{k}"] = {"x": [0, y, p.height], "body": lift_name(k, len(p.lifts()))}
        points[f"heel_m{k}"] = {"x": [0, y, 0], "body": f"m{k}"}
        points[f"toe_m{k}"] = {"x": [p.base, y, 0], "body": f"m{k}"}
    out = {"title": f"gravity dam: {n} monoliths, H = {p.height:g} m, {analysis}",
           "meshes": {"m": "dam.msh"}, "bodies": bodies, "couples": couples, "dirichlet": dirichlet, "loads": loads,
           "output": {"fields": ["displacement", "stress"], "points": points}}
    if absorbing:
        out["absorbing"] = absorbing
    if p.added_mass and analysis != "static":
        out["added_mass"] = [{"surface": "upstream", "density": WATER / G, "level": p.water, "bottom": 0.0}]
    if seismic:
        out["output"]["fields"].append("envelope")
    if analysis == "dynamic":
        loads.append(ground_motion(p, record, eq_start))
        out["analysis"] = {"type": "dynamic", "dt": dt, "final_time": eq_start + eq_duration,
                           "newmark": {"beta": 0.3025, "gamma": 0.6}}
        out["output"]["every"] = every
    elif analysis == "modal":
        out["loads"] = []
        out["analysis"] = {"type": "modal", "modes": 10}
        out["output"]["fields"] = ["displacement", "stress"]
    elif staged:
        quake = ground_motion(p, record, float(steps))
        out["stages"] = [{"name": "static", "analysis": {"type": "static"} if steps == 1 else {"type": "static", "dt": 1.0, "final_time": float(steps)}},
                         {"name": "earthquake", "analysis": {"type": "dynamic", "dt": dt, "final_time": steps + eq_duration,
                                                             "newmark": {"beta": 0.3025, "gamma": 0.6}},
                          "loads": [quake]}]
        out["output"]["every"] = every
    else:
        out["analysis"] = {"type": "static"} if steps == 1 else {"type": "static", "dt": 1.0, "final_time": float(steps)}
    return out


def write_records(p, outdir, record, record_from):
    """The records of the ground motion's components beside the scene: x the synthetic record
    (meshes/dam/ground_motion.csv), y another one (seed 7), z two thirds of a third one (seed 8),
    or the .AT2 files given; record_from > 0 copies a CSV record from that time on (its first
    value set to 0: from rest)."""
    import ground_motion  # noqa: E402 (beside this script)

    for i, c in enumerate(p.components):
        if i < len(p.at2):
            if record_from > 0:
                raise ValueError("record_from cuts the synthetic records, not an .AT2 (shift it instead)")
            shutil.copy(p.at2[i], os.path.join(outdir, os.path.basename(p.at2[i])))
            continue
        name = record if c == "x" else record.replace(".csv", f"_{c}.csv")
        if c == "x":
            t, a = ground_motion.read(RECORD)
        else:
            t, a = ground_motion.record(seed=7 if c == "y" else 8, pga=0.3 if c == "y" else 0.2)
        keep = t >= record_from - 1e-9
        t, a = t[keep] - t[keep][0], a[keep].copy()
        if record_from > 0:
            a[0] = 0.0
        with open(os.path.join(outdir, name), "w") as f:
            f.write(f"# {c}: synthetic ground acceleration (meshes/dam/ground_motion.py) from t = {record_from:g} s\nt,a_g\n")
            f.write("".join(f"{ti:.4f},{v:.7e}\n" for ti, v in zip(t, a)))


def build(outdir, analysis="static", target_dofs=None, binary=None, quiet=True, dt=0.01, ramp=1.0, eq_start=2.0,
          eq_duration=20.0, record_from=0.0, every=10, **params):
    """Writes OUTDIR/dam.msh, dam.yaml, dam.h5 (and the record for a dynamic analysis); returns
    the scene file. params: the fields of Dam; target_dofs overrides h. Dynamic: the loads are
    ramped over `ramp` s, the record starts at eq_start and runs eq_duration s; record_from > 0
    copies the record from that time on (its first value set to 0: from rest), to put a short
    run into the strong motion. build.info (also OUTDIR/dam.json) holds the parameters, DOF
    count, weight, thrust and times of the last call."""
    p = Dam(**params).check()
    if p.joints is None:  # a static analysis with contact between two bodies held only by contact does not converge yet
        p = replace(p, joints=analysis in ("dynamic", "modal"))
    if p.sliding is None:  # an earthquake slides the joints by millimetres under faces of metres (docs/dam.md)
        p = replace(p, sliding="small" if analysis in ("dynamic", "staged") else "finite")
    if p.sliding not in ("small", "finite"):
        raise ValueError(f"sliding {p.sliding!r}: small or finite")
    if target_dofs:
        p = replace(p, h=size_for_dofs(p, target_dofs))
    os.makedirs(outdir, exist_ok=True)
    a = layout(p)
    dofs = count_dofs(p)
    binary = dofs > 200000 if binary is None else binary
    t0 = time.perf_counter()
    vertices = write_mesh(os.path.join(outdir, "dam.msh"), p, a, binary)
    t1 = time.perf_counter()
    record = "ground_motion.csv"
    if analysis in ("dynamic", "staged"):
        write_records(p, outdir, record, record_from)
    h5 = prepare(outdir, "dam", scene(p, analysis, dt, ramp, eq_start, eq_duration, record, every))
    t2 = time.perf_counter()
    build.info = dict(params=asdict(p), analysis=analysis, dofs=dofs, vertices=vertices, h=p.h, nx=a["nx"], ny=a["ny"],
                      nz=a["nz"], mesh_seconds=t1 - t0, prep_seconds=t2 - t1, weight=p.weight(), thrust=p.thrust(),
                      couples=couple_names(p), eq_start={"dynamic": eq_start, "staged": float(p.load_steps())}.get(analysis))
    with open(os.path.join(outdir, "dam.json"), "w") as f:  # for meshes/dam/report.py
        json.dump(build.info, f, indent=1)
    if not quiet:
        print(f"{dofs} DOFs ({vertices} vertices), h = {p.h:.4g} m: monolith {a['nx']} x {a['ny']} x {a['nz']}, "
              f"foundation {len(a['fx']) - 1} x {len(a['fy']) - 1} x {len(a['fz']) - 1}; mesh {t1 - t0:.1f} s, prep {t2 - t1:.1f} s")
    return h5


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("outdir")
    size = ap.add_mutually_exclusive_group()
    size.add_argument("--h", type=float, help="element size in the dam, m (default 5)")
    size.add_argument("--dofs", type=float, help="target number of DOFs instead of --h")
    ap.add_argument("--monoliths", type=int, default=Dam.monoliths)
    ap.add_argument("--height", type=float, default=Dam.height)
    ap.add_argument("--crest", type=float, default=Dam.crest)
    ap.add_argument("--slope", type=float, default=Dam.slope, help="downstream face H:V")
    ap.add_argument("--width", type=float, default=Dam.width, help="monolith length along the axis")
    ap.add_argument("--level", type=float, default=0.0, help="reservoir level above the base (default 0.95 height)")
    ap.add_argument("--mu-base", type=float, default=Dam.mu_base)
    ap.add_argument("--mu-joint", type=float, default=Dam.mu_joint)
    ap.add_argument("--cohesion-base", type=float, default=0.0, help="the base bonded: its cohesion, Pa (docs/dam.md, Bonded joints)")
    ap.add_argument("--tensile-base", type=float, default=None, help="the base's tensile strength, Pa (default cohesion / mu-base; 0 is FERC's without tests)")
    ap.add_argument("--cohesion-lift", type=float, default=0.0, help="the lift joints bonded: their cohesion, Pa")
    ap.add_argument("--tensile-lift", type=float, default=None, help="the lift joints' tensile strength, Pa (default cohesion / mu-joint)")
    ap.add_argument("--mu-residual", type=float, default=None, help="friction of a broken bond (default the joint's mu)")
    ap.add_argument("--softening", type=float, default=0.0, help="the bonds soften over this relative displacement, m (default 0: brittle)")
    ap.add_argument("--sides", choices=("normal", "all", "none"), default=Dam.sides)
    ap.add_argument("--no-floor", action="store_true", help="no water pressure on the reservoir floor")
    ap.add_argument("--dynamic", action="store_true", help="ramp the static loads, then the ground motion record")
    ap.add_argument("--quasi-static", action="store_true",
                    help="dynamic, the static loads ramped over 1 s and held to 2 s, no record: the static state "
                         "with joints and partial slip (docs/dam.md)")
    ap.add_argument("--staged", action="store_true",
                    help="a static stage (self-weight and water), then the ground motion record from that state")
    ap.add_argument("--eq-duration", type=float, default=20.0, help="s of the record to run")
    ap.add_argument("--joints", action=argparse.BooleanOptionalAction, default=None,
                    help="contraction joints as contact couples (default: in dynamic analyses only)")
    ap.add_argument("--sliding", choices=("small", "finite"), default=None,
                    help="the couples' sliding (default: small in dynamic and staged analyses, finite in static ones)")
    ap.add_argument("--binary", action="store_true", default=None, help="binary Gmsh file (default above 200k DOFs)")
    ap.add_argument("--modal", action="store_true", help="the first 10 natural frequencies and modes (couples tied)")
    ap.add_argument("--added-mass", action="store_true", help="the reservoir's Westergaard added mass on the upstream faces")
    ap.add_argument("--foundation", choices=("massed", "massless", "radiating"), default="massed",
                    help="the rock's inertia and base: massed (fixed base), massless, or radiating (absorbing "
                         "boundaries, the record entering at the bottom as the outcrop motion; --staged)")
    ap.add_argument("--components", choices=("x", "xy", "xyz"), default="x", help="ground motion components")
    ap.add_argument("--at2", nargs="+", default=(), help="PEER .AT2 records for x (and y, z) instead of the synthetic ones")
    lift = ap.add_mutually_exclusive_group()
    lift.add_argument("--lift-joints", type=int, default=0, metavar="N",
                      help="N horizontal lift joints through every monolith, evenly spaced (H / (N + 1) apart), as contact couples")
    lift.add_argument("--lift-heights", nargs="+", type=float, default=(), metavar="Z", help="the lift joints' heights, m")
    ap.add_argument("--uplift", action="store_true",
                    help="the water pressure under the base and in the lift joints (heel-to-toe law with drains, "
                         "water entering open joints: docs/dam.md)")
    ap.add_argument("--tail-water", type=float, default=Dam.tail_water, help="tail water above the base, m (default 0)")
    ap.add_argument("--drains", type=float, default=Dam.drains,
                    help="the drain line's distance from the heel / the joint's length (default 0.05; 0: no drains)")
    ap.add_argument("--drain-efficiency", type=float, default=Dam.drain_efficiency, help="default 0.5 (USACE, FERC)")
    ap.add_argument("--no-penetration", action="store_true", help="no water entering the joints as they open")
    ap.add_argument("--static-steps", type=int, default=0,
                    help="static load steps (default 1; 12 with uplift: the reservoir raised over the first half, held over the rest, the water entering the opening joints step by step)")
    a = ap.parse_args()
    lifts = tuple(a.lift_heights) or tuple(a.height * j / (a.lift_joints + 1) for j in range(1, a.lift_joints + 1))
    params = dict(monoliths=a.monoliths, height=a.height, crest=a.crest, slope=a.slope, width=a.width, level=a.level,
                  mu_base=a.mu_base, mu_joint=a.mu_joint, sides=a.sides, floor=not a.no_floor, joints=a.joints, sliding=a.sliding,
                  added_mass=a.added_mass, foundation_model=a.foundation, components=a.components, at2=tuple(a.at2),
                  lift_joints=lifts, uplift=a.uplift, tail_water=a.tail_water, drains=a.drains,
                  drain_efficiency=a.drain_efficiency, penetration=not a.no_penetration, static_steps=a.static_steps,
                  cohesion_base=a.cohesion_base, tensile_base=a.tensile_base, cohesion_lift=a.cohesion_lift,
                  tensile_lift=a.tensile_lift, mu_residual=a.mu_residual, softening=a.softening)
    if a.h:
        params["h"] = a.h
    extra = dict(dt=0.02, eq_duration=0.0) if a.quasi_static else dict(eq_duration=a.eq_duration)
    analysis = "modal" if a.modal else ("staged" if a.staged else ("dynamic" if a.dynamic or a.quasi_static else "static"))
    try:
        h5 = build(a.outdir, analysis, target_dofs=a.dofs, binary=a.binary, quiet=False, **extra, **params)
    except ValueError as e:  # the dam's parameters: a message, not a traceback
        ap.error(str(e))
    print(h5)
