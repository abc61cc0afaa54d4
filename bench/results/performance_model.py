#!/usr/bin/python3
"""The performance model of docs/performance-model.md: fitted constants from the measured dam runs
(the MEASURED tables below, copied from the runs that section lists: -log_view, MUMPS's own
statistics with -mat_mumps_icntl_4 2, -info), and the extrapolations (the 1M-DOF dam on the
2-core machine, the 100M-DOF dam on 1000 ranks) computed from them by the formulas printed with
each figure. No number here is typed in that was not measured or follows from a formula below.

  bench/results/performance_model.py            # the tables of docs/performance-model.md
"""
import math
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import dam_sizes  # noqa: E402

GB = 1e9
# ---------------------------------------------------------------------------------------------
# MEASURED (one rank, the shared 2-core machine, 2 Dec 2026; docs/performance-model.md, "Runs").
# MUMPS factorizations of single bodies: (N_b, |C| Schur size or 0, flops RINFOG(3), nnz(L) INFOG(29),
# memory used MB INFOG(22), factorization time s). Static dam, no joints, foundation:
FOUND = [(12936, 0, 2.266e9, 4496037, 50, 0.166), (27972, 0, 1.145e10, 13978494, 139, 0.637),
         (49632, 0, 3.196e10, 30104211, 298, 2.296), (95004, 0, 1.051e11, 72959526, 701, 5.835),
         (184704, 0, 6.020e11, 210640737, 2013, 27.234), (137088, 0, 2.536e11, 126541944, 1154, 10.607)]
FOUND_S = [(12936, 1020, 5.380e9, 6030405, 78, 0.311), (27972, 1584, 2.531e10, 19361565, 227, 1.853),
           (49632, 2352, 1.159e11, 50606736, 578, 5.518), (95004, 3672, 5.883e11, 144862569, 1673, 21.071),
           (184704, 5676, 2.265e12, 361167867, 3993, 84.163), (137088, 4800, 1.047e12, 229498770, 2575, 31.499)]
# monoliths (4e5 no joints; 2e4 ... 3e5 with joints: m1 one joint, m2 two joints); the foundation's
# 137 088-DOF rows are the 3e5 runs' (the same mesh with and without joints)
MONO = [(53280, 0, 3.764e10, 34107777, 326, 2.32), (55860, 0, 3.520e10, 34569813, 340, 2.14),
        (11484, 0, 1.469e9, 3608811, 40, 0.145), (12420, 0, 1.719e9, 3990807, 44, 0.162),
        (5040, 0, 4.196e8, 1251378, 15, 0.044), (5610, 0, 7.165e8, 1725927, 19, 0.062), (2016, 0, 6.386e7, 314253, 5, 0.007),
        (24864, 0, 7.991e9, 11305749, 115, 0.549), (26448, 0, 9.313e9, 12318726, 130, 0.651),
        (39474, 0, 1.908e10, 21441924, 214, 1.267), (41580, 0, 2.245e10, 23600970, 235, 1.460)]
MONO_S = [(53280, 1110, 1.506e11, 59654028, 626, 6.895), (55860, 1140, 1.344e11, 59112891, 579, 4.706),
          (11484, 2016, 9.207e9, 6603777, 109, 0.530), (12420, 4416, 3.267e10, 10987287, 319, 1.437),
          (11484, 3636, 1.790e10, 7594641, 220, 0.716), (12420, 2415, 1.409e10, 8406318, 145, 0.547),
          (5610, 2397, 2.969e9, 2180151, 77, 0.212), (2016, 1080, 3.265e8, 432180, 17, 0.039),
          (24864, 3402, 4.526e10, 20385453, 330, 1.964), (24864, 6132, 1.123e11, 29121279, 664, 4.113),
          (26448, 3915, 8.708e10, 30244953, 481, 4.931), (26448, 7134, 1.554e11, 33708204, 864, 7.444),
          (39474, 4854, 1.498e11, 44421069, 721, 6.250), (39474, 8790, 3.345e11, 59852445, 1420, 10.453),
          (41580, 5460, 2.534e11, 61080360, 973, 10.446), (41580, 9975, 2.363e11, 46755543, 1394, 12.645)]
# Newton matrices (MUMPS LU): (order n, nnz(J), flops, nnz(L+U), MB, s). No joints: dense.
NEWTON = [(576, 309880, 1.272e8, 331776, 7, 0.005), (1014, 989166, 6.945e8, 1028196, 20, 0.022),
          (1644, 2639544, 2.961e9, 2702736, 54, 0.083), (2760, 7511256, 1.401e10, 7617600, 163, 0.392),
          (4524, 20292024, 6.172e10, 20466576, 438, 1.980)]
NEWTON_J = [(2868, 5735814, 9.154e9, 6578766, 135, 0.328), (5517, 21248429, 6.219e10, 23823081, 490, 1.835),
            (3789, 9819797, 1.979e10, 11152161, 228, 0.519), (6498, 30545252, 1.182e11, 35100756, 717, 3.615),
            (8364, 47231686, 1.965e11, 52369182, 1069, 5.971), (8778, 57006838, 2.755e11, 62138844, 1269, 6.474),
            (11859, 94637595, 5.499e11, 104354775, 2128, 12.614)]
# phases of the static dam, no joints, one rank (s): DOFs, assemble, D, D products (MatMatMultNum), search, output, RSS MiB
PHASES = [(20400, 0.904, 0.493, 0.046, 0.012, 0.144, 298), (49272, 2.385, 2.714, None, 0.028, 0.213, 713),
          (97440, 4.068, 8.381, None, 0.045, 0.914, 1567), (197628, 8.386, 31.157, 2.875, 0.067, 0.910, 3934),
          (402984, 23.869, 142.410, 16.855, 0.179, 3.271, 9801)]
GEMM = [(1.53e11, 2.875), (6.03e11, 16.855), (5.93e11, 12.129)]  # S^-1 H_C products: flops, s (2e5, 4e5 no joints; 1e5 joints)
# dynamic dam with joints, 100 steps: D builds and Newton factorizations at 20 400 and 49 272 DOFs;
# at 20 400 the body solves (count, s) and the five bodies' nnz(L) (MUMPS INFOG(29));
# static with joints (2e4, 5e4, 1e5): Newton factorizations
DYN = dict(builds=(83, 94), lus=(384, 462), solves=500, solve_s=1.784, nnzl=4496037 + 2 * 240159 + 2 * 314253)
STATIC_LUS_J = (8, 9)
# adding the dense D_i into the AIJ W (MatSetValues, preallocated), s per entry of sum_b m_b^2 per build:
# the rest of MBCFlexibilityAssemble after the Schur factorizations (MUMPS's times), the products
# (MatMatMultNum, MatTrnMatMultNum), potrf/potri (sum |C|^3 at 28-38 GFlop/s) and the symbolic
# factorizations: 400k no joints 13.7 - 5.9 - 1.2 s over 2 x 2.53e7 entries = 130 ns;
# 200k joints 61.1 - 23 - 1 s over 2 x 1.06e8 entries = 175 ns (+- the potrf/potri rate: 160-190)
W_ADD = (130e-9, 190e-9)
SOLVE_RATE = 4 * DYN["nnzl"] * DYN["solves"] / DYN["solve_s"]  # one-right-side solves: 4 nnz(L) flops each
# flops/s of KSPMatSolve (4 nnz(L) flops a column): the 97 440-DOF static dam with -mbc_d_route multirhs,
# 2 builds of the foundation's 1 620 columns and the monoliths' 396 / 414, KSPMatSolve 30.53 s
MRHS_RATE = 2 * 4 * (1620 * 30104211 + 2 * 396 * 3608811 + 2 * 414 * 3990807) / 30.53


def fit(x, y):
    """y = a x^b by log-log least squares: (a, b)."""
    b, la = np.polyfit(np.log(np.asarray(x, float)), np.log(np.asarray(y, float)), 1)
    return math.exp(la), b


def rng(vals):
    return min(vals), max(vals)


# ---------------------------------------------------------------------------------------------
ALL = [r for r in FOUND + MONO if r[0] > 25000]                      # the bodies above 25k DOFs
C_F = rng([f / n ** 2 for n, _, f, *_ in ALL])                      # body factor flops / N^2
C_L = rng([l / n ** (4 / 3) for n, _, _, l, *_ in ALL])             # nnz(L) / N^(4/3)
MEMF = rng([mb * 1e6 / (8 * l) for n, _, _, l, mb, _ in ALL if n > 20000])   # MUMPS memory / (8 nnz(L))
R_FACT = rng([f / t for n, _, f, _, _, t in FOUND[2:]])             # flop rate of body factorizations
R_SCHUR = rng([f / t for n, _, f, _, _, t in FOUND_S[2:]])
R_LU = rng([f / t for n, _, f, _, _, t in NEWTON[2:] + NEWTON_J])
R_GEMM = rng([f / t for f, t in GEMM])
MEM_LU = rng([mb * 1e6 / n ** 2 for n, _, _, _, mb, _ in NEWTON[2:]])  # bytes per n^2 (dense)
LU_DENS = rng([f / (2 / 3 * n ** 3) for n, _, f, *_ in NEWTON_J])      # joints: flops / dense LU's
FS_FIT = fit([r[0] for r in FOUND_S], [r[2] for r in FOUND_S])        # foundation Schur factor flops ~ N^b
FSM_FIT = fit([r[0] for r in FOUND_S], [r[4] for r in FOUND_S])       # its memory (MB) ~ N^b
RHO = sorted((c / n, fs / f) for (n, c, fs, *_), (_, _, f, *_) in
             [(s, [b for b in MONO if b[0] == s[0]][0]) for s in MONO_S])  # (|C|/N, Schur flops / body flops)
ASM = rng([t / n for n, t, *_ in PHASES[3:]])                        # assembly s per DOF (largest sizes)
OUT = rng([o / n for n, _, _, _, _, o, _ in PHASES[2:]])
SEARCH_PT = 0.179 / 1500 / 3                                         # s per contact point per search (4e5: 3 searches)
KA_BYTES = 2 * 75 * 12                                               # K and the factored copy A in AIJ, per DOF
OTHER = rng([(rss * 2 ** 20 - est) / n for n, rss, est in
             [(402984, 9801, (2013 + 2 * 326 + 2 * 340 + 3993 + 5676 ** 2 * 8 / 1e6) * 1e6 + KA_BYTES * 402984)]])


def show_constants():
    print("## fitted constants (from the MEASURED tables)")
    print(f"body factor flops / N^2            {C_F[0]:.1f} .. {C_F[1]:.1f}")
    print(f"nnz(L) / N^(4/3)                    {C_L[0]:.1f} .. {C_L[1]:.1f}")
    print(f"MUMPS memory / (8 nnz(L))           {MEMF[0]:.2f} .. {MEMF[1]:.2f}")
    print(f"rates GFlop/s: body factor {R_FACT[0] / 1e9:.0f}..{R_FACT[1] / 1e9:.0f}, Schur factor {R_SCHUR[0] / 1e9:.0f}..{R_SCHUR[1] / 1e9:.0f}, "
          f"Newton LU {R_LU[0] / 1e9:.0f}..{R_LU[1] / 1e9:.0f}, S^-1 H_C products {R_GEMM[0] / 1e9:.0f}..{R_GEMM[1] / 1e9:.0f}, multi-RHS solves {MRHS_RATE / 1e9:.0f}")
    print(f"foundation Schur factor flops = {FS_FIT[0]:.3g} N^{FS_FIT[1]:.2f}; its memory MB = {FSM_FIT[0]:.3g} N^{FSM_FIT[1]:.2f}")
    print("Schur / body factor flops against |C|/N: " + ", ".join(f"{a:.3f}: {b:.1f}" for a, b in RHO))
    for n, c, fs, *_ in FOUND_S:
        f = [r[2] for r in FOUND if r[0] == n][0]
        print(f"   foundation N {n}: |C|/N {c / n:.3f}, ratio {fs / f:.1f}")
    print(f"single solves {SOLVE_RATE / 1e9:.1f} GFlop/s (4 nnz(L) flops a solve)")
    print(f"Newton LU memory bytes / n^2 (dense) {MEM_LU[0]:.1f} .. {MEM_LU[1]:.1f}; joints: LU flops / (2/3 n^3) {LU_DENS[0]:.2f} .. {LU_DENS[1]:.2f}")
    print(f"assembly s/DOF {ASM[0]:.2e} .. {ASM[1]:.2e}; output s/DOF {OUT[0]:.1e} .. {OUT[1]:.1e}; search s/point/search {SEARCH_PT:.1e}")
    print(f"other memory (meshes, vectors, PETSc objects) bytes/DOF at 4e5: {OTHER[0]:.0f}")


def schur_ratio(frac):
    """Schur / body factor flops for a body with |C|/N = frac: the range of the measured ratios of
    the bodies whose |C|/N brackets frac (the nearest below and above; monoliths and foundation)."""
    pts = RHO + [(c / n, fs / [r[2] for r in FOUND if r[0] == n][0]) for n, c, fs, *_ in FOUND_S]
    below = [p for p in pts if p[0] <= frac]
    above = [p for p in pts if p[0] >= frac]
    near = ([max(below)] if below else []) + ([min(above)] if above else [])
    return rng([p[1] for p in near])


# ---------------------------------------------------------------------------------------------
def one_million(joints=True, schur_max_mb=2048, target=1e6):
    """The dam of `target` DOFs (1M) on this machine, one rank, the current routes (-mbc_d_route auto)."""
    s = dam_sizes.sizes(target, joints)
    print(f"\n## {target:.0e}-DOF dam, {'joints' if joints else 'no joints'}: N {s['N']}, m {s['m']}, nnz(W) {s['nnzW']:.3e}")
    t = {}
    mem = {}
    t["assemble"] = (ASM[0] * s["N"], ASM[1] * s["N"])
    fl = [sum(c * b["N"] ** 2 for b in s["bodies"].values()) for c in C_F]
    t["factor"] = (fl[0] / R_FACT[1], fl[1] / R_FACT[0])
    mem["factors"] = tuple(MEMF[1] * 8 * c * sum(b["N"] ** (4 / 3) for b in s["bodies"].values()) for c in C_L)
    schur_t, schur_mem, sinv_t, prod_t, mrhs_t, sinv_mem = [0, 0], [0, 0], [0, 0], [0, 0], [0, 0], 0
    routes = {}
    for name, b in s["bodies"].items():
        if b["C"] ** 2 * 8 / 2 ** 20 <= schur_max_mb:
            routes[name] = "Schur"
            if name == "foundation":
                fs = FS_FIT[0] * b["N"] ** FS_FIT[1]
                fsr = (fs, fs)
                mws = FSM_FIT[0] * b["N"] ** FSM_FIT[1] * 1e6
                mwr = (mws, mws)
            else:
                r = schur_ratio(b["C"] / b["N"])
                fsr = (r[0] * C_F[0] * b["N"] ** 2, r[1] * C_F[1] * b["N"] ** 2)
                mwr = tuple(m * 8 * c * b["N"] ** (4 / 3) * 2 for m, c in zip(MEMF, C_L))  # Schur factor ~ 2 x the body's (measured 1.7-2.9 x)
            schur_t = [schur_t[0] + fsr[0] / R_SCHUR[1], schur_t[1] + fsr[1] / R_SCHUR[0]]
            schur_mem = [max(schur_mem[0], mwr[0]), max(schur_mem[1], mwr[1])]
            sinv_t = [sinv_t[0] + b["C"] ** 3 / R_LU[1], sinv_t[1] + b["C"] ** 3 / R_LU[0]]
            sinv_mem += 8 * b["C"] ** 2
            pr = 2 * b["C"] ** 2 * 3 * b["p"]
            prod_t = [prod_t[0] + pr / R_GEMM[1], prod_t[1] + pr / R_GEMM[0]]
        else:
            routes[name] = "multi-RHS"
            fl = [4 * c * b["N"] ** (4 / 3) * 3 * b["p"] for c in C_L]
            mrhs_t = [mrhs_t[0] + fl[0] / MRHS_RATE, mrhs_t[1] + fl[1] / MRHS_RATE]
    print("routes: " + ", ".join(f"{k} {v} (N {b['N']}, |C| {b['C']}, m_b {3 * b['p']})" for (k, v), b in zip(routes.items(), s["bodies"].values())))
    t["D: Schur factorizations (once)"] = tuple(schur_t)
    t["D: S^-1 (potrf+potri, once)"] = tuple(sinv_t)
    t["D: products per build"] = tuple(prod_t)
    t["D: multi-RHS solves per build"] = tuple(mrhs_t)
    mb2 = sum((3 * b["p"]) ** 2 for b in s["bodies"].values())
    t["D: D_i into W per build"] = (W_ADD[0] * mb2, W_ADD[1] * mb2)
    n = s["m"] + 24
    lu = (LU_DENS[0] * 2 / 3 * (0.6 * n) ** 3, LU_DENS[1] * 2 / 3 * (0.85 * n) ** 3) if joints else (2 / 3 * n ** 3,) * 2
    t["Newton LU, each"] = (lu[0] / R_LU[1], lu[1] / R_LU[0])
    t["search, each"] = (SEARCH_PT * s["points"],) * 2
    t["output, each"] = (OUT[0] * s["N"], OUT[1] * s["N"])
    mem["K and A"] = (KA_BYTES * s["N"],) * 2
    mem["other"] = (OTHER[0] * s["N"],) * 2
    mem["S^-1 (Schur bodies)"] = (sinv_mem,) * 2
    mem["Schur factorization workspace (largest)"] = tuple(schur_mem)
    mem["W (AIJ, 12 B/entry)"] = (12 * s["nnzW"],) * 2
    nA = (0.6 * n, 0.85 * n) if joints else (n, n)
    dens = s["nnzW"] / s["m"] ** 2
    mem["Newton J (AIJ)"] = (12 * dens * nA[0] ** 2, 12 * dens * nA[1] ** 2)
    mem["Newton LU (MUMPS)"] = (MEM_LU[0] * nA[0] ** 2, MEM_LU[1] * nA[1] ** 2)
    nnzl = [c * sum(b["N"] ** (4 / 3) for b in s["bodies"].values()) for c in C_L]
    t["body solves, each (all bodies)"] = (4 * nnzl[0] / SOLVE_RATE, 4 * nnzl[1] / SOLVE_RATE)
    for k, v in t.items():
        print(f"  time  {k:40s} {v[0]:9.0f} .. {v[1]:9.0f} s")
    once = [t["assemble"][i] + t["factor"][i] + t["D: Schur factorizations (once)"][i] + t["D: S^-1 (potrf+potri, once)"][i] for i in (0, 1)]
    build = [t["D: products per build"][i] + t["D: multi-RHS solves per build"][i] + t["D: D_i into W per build"][i] for i in (0, 1)]
    lus = STATIC_LUS_J if joints else (2, 2)
    static = [once[i] + 2 * build[i] + lus[i] * t["Newton LU, each"][i] + 3 * t["output, each"][i] + 15 * t["body solves, each (all bodies)"][i] for i in (0, 1)]
    dyn = [once[i] + DYN["builds"][i] * build[i] + DYN["lus"][i] * t["Newton LU, each"][i] + DYN["solves"] / 5 * t["body solves, each (all bodies)"][i]
           + 11 * t["output, each"][i] for i in (0, 1)]
    print(f"  static solve (2 D builds, {lus[0]}-{lus[1]} Newton LUs, 15 body solves, 3 outputs): {static[0] / 3600:.1f} .. {static[1] / 3600:.1f} h ({static[0]:.0f} .. {static[1]:.0f} s)")
    print(f"  100 dynamic steps ({DYN['builds'][0]}-{DYN['builds'][1]} D builds, {DYN['lus'][0]}-{DYN['lus'][1]} Newton LUs as at 20k-50k, {DYN['solves']} body solves): {dyn[0] / 3600:.1f} .. {dyn[1] / 3600:.1f} h")
    for k, v in mem.items():
        print(f"  mem   {k:40s} {v[0] / GB:9.1f} .. {v[1] / GB:9.1f} GB")
    base = [mem["K and A"][i] + mem["other"][i] + mem["factors"][i] + mem["S^-1 (Schur bodies)"][i] for i in (0, 1)]
    dpk = [base[i] + mem["Schur factorization workspace (largest)"][i] + mem["W (AIJ, 12 B/entry)"][i] for i in (0, 1)]
    npk = [base[i] + mem["W (AIJ, 12 B/entry)"][i] + mem["Newton J (AIJ)"][i] + mem["Newton LU (MUMPS)"][i] for i in (0, 1)]
    print(f"  peak during D {dpk[0] / GB:.1f} .. {dpk[1] / GB:.1f} GB; during the Newton solve {npk[0] / GB:.1f} .. {npk[1] / GB:.1f} GB")
    return s, t, mem


def hundred_million(joints=True, P=1000, per_rank=1e5, flops=10e9, bw=10e9):
    """The dam refined to 1e8 DOFs on P ranks, each body over N_b / per_rank ranks (the current
    decomposition), 10 GFlop/s per core, 10 GB/s per rank: per rank, perfect parallel efficiency
    (lower bounds on time)."""
    s = dam_sizes.sizes(1e8, joints)
    m, nnzW = s["m"], s["nnzW"]
    print(f"\n## 100M-DOF dam, {'joints' if joints else 'no joints'}, {P} ranks: N {s['N']}, points {s['points']}, m {m}, nnz(W) {nnzW:.3e}")
    B = s["bodies"]
    for k, b in B.items():
        b["P"] = max(1, int(b["N"] // per_rank))
    rows = {}
    tot = 0
    for k, b in B.items():
        print(f"  {k:10s} N_b {b['N']:.3e} ranks {b['P']:4d} |C| {b['C']:7d} m_b {3 * b['p']:7d}")
    f = max(B.values(), key=lambda b: b["N"])
    cf, cl = sum(C_F) / 2, sum(C_L) / 2
    fac = cf * f["N"] ** 2 / (f["P"] * flops)
    nnzl = cl * f["N"] ** (4 / 3)
    print(f"  body factor (largest body, {f['P']} ranks): {cf * f['N'] ** 2:.2e} flops -> {fac:.0f} s; nnz(L) {nnzl:.2e} -> {MEMF[1] * 8 * nnzl / f['P'] / GB:.1f} GB per rank")
    fs1 = cf * per_rank ** 2 / flops
    print(f"  body factor if every body had {per_rank:.0e} DOFs on one rank: {fs1:.0f} s, {MEMF[1] * 8 * cl * per_rank ** (4 / 3) / GB:.2f} GB")
    # D: multi-RHS on distributed bodies (the Schur route is one-rank only)
    worst = 0
    for k, b in B.items():
        fl = 4 * cl * b["N"] ** (4 / 3) * 3 * b["p"]
        worst = max(worst, fl / (b["P"] * flops))
    print(f"  D by multi-RHS solves, slowest body: {worst:.2e} s per build (4 nnz(L) m_b flops over its ranks)")
    sum_mb2 = sum((3 * b["p"]) ** 2 for b in B.values())
    print(f"  D_i dense blocks: sum m_b^2 = {sum_mb2:.2e} entries = {8 * sum_mb2 / GB:.0f} GB; into W by MatSetValues/stash "
          f"(16 B an entry off-rank): up to {16 * sum_mb2 / 1e12:.1f} TB per build, {16 * sum_mb2 / P / GB:.1f} GB per rank on average")
    # rows of W: on the ranks of the point's master body
    wr = max(B.values(), key=lambda b: b["row_nnz"] / b["P"])
    print(f"  W: {12 * nnzW / 1e12:.2f} TB in AIJ; its rows on the master bodies' ranks only: up to {12 * wr['row_nnz'] / wr['P'] / GB:.1f} GB per rank "
          f"({wr['rows']} rows over {wr['P']} ranks); {12 * nnzW / P / GB:.1f} GB if spread over all {P} ranks")
    # matrix-free W v (one solve per body with its factor, SF exchange of H columns): bodies of per_rank DOFs on one rank
    solve1 = 4 * sum(C_L) / 2 * per_rank ** (4 / 3) / SOLVE_RATE
    print(f"  matrix-free W v with bodies of {per_rank:.0e} DOFs on one rank: one solve each, {solve1:.3f} s at the measured {SOLVE_RATE / 1e9:.1f} GFlop/s; "
          f"exchange 2 x m_b x 8 B per body and product")
    n = m + 6 * 4
    lu = (LU_DENS[0] if joints else 1.0) * 2 / 3 * n ** 3
    print(f"  Newton LU of n = {n}: {lu:.2e} flops -> {lu / flops:.2e} s on each rank (PCREDUNDANT), {lu / (P * flops):.2e} s if perfectly distributed")
    print(f"  Newton LU memory {MEM_LU[1] * n ** 2 / GB:.0f} GB on each rank (redundant), {MEM_LU[1] * n ** 2 / P / GB:.1f} GB per rank distributed")
    print(f"  redundant gather of J per factorization: each rank receives nnz(J) x 12 B = {12 * nnzW / 1e12:.2f} TB; all ranks {P * 12 * nnzW / 1e15:.1f} PB")
    print(f"  per Newton iteration, W r products: <= m x 8 B = {8 * m / 1e6:.1f} MB received per rank per product; "
          f"ISAllGather of the active set {4 * m / 1e6:.1f} MB per rank; right side / solution to every rank {8 * m / 1e6:.1f} MB")
    faces = 2 * s["points"]
    print(f"  search: Allgatherv of every contact face (~2 x points = {faces}, ~120 B each) {120 * faces / 1e6:.0f} MB per rank per search; "
          f"replicated search {SEARCH_PT * s['points']:.1f} s per search")
    print(f"  assembly {ASM[0] * per_rank:.1f} .. {ASM[1] * per_rank:.1f} s per rank; output {OUT[0] * per_rank:.2f} .. {OUT[1] * per_rank:.2f} s per rank per output")
    return s


if __name__ == "__main__":
    if len(sys.argv) > 1:  # a prediction at another size: performance_model.py 2e5 [joints]
        one_million(joints="joints" in sys.argv[2:], target=float(sys.argv[1]))
        sys.exit(0)
    show_constants()
    one_million(joints=True)
    one_million(joints=False)
    hundred_million(joints=True)
    hundred_million(joints=False)
