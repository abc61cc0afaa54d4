"""Extreme static cases of bench/extremes.py (docs/stability.md), one per category that passes:
a block on a base, nu = 0, frictionless unless stated, whose exact answer is uniaxial stress
(hex8i represents it exactly): top u_z = -p (L/E_base + L/(2 E_block)), contact force p L^2.
Tolerance 1e-8 relative: the multiplier tolerance (1e-8 of the step's free gap increment) is the
only inexact part; measured errors 1e-16..3e-12. About 5 s in all."""
import pytest

from conftest import load_script

bench = load_script("bench/extremes.py", "bench_extremes")


def errors(res):
    uz, fz, uz_ex, fz_ex, out, _ = res
    assert uz is not None, out
    assert "DIVERGED" not in out, out
    return abs(uz / uz_ex - 1), abs(fz / fz_ex - 1)


@pytest.mark.parametrize("case", ["contrast 1e6", "contrast 1e-6", "size 1e4", "size 1e-3", "friction 10", "ratio 20:1"])
def test_extreme_static_case_is_exact(tmp_path, case):
    kw = {"contrast 1e6": dict(E_block=2e16, p=2e6), "contrast 1e-6": dict(E_block=2e4, p=2.0),
          "size 1e4": dict(L=1e4), "size 1e-3": dict(L=1e-3),
          "friction 10": dict(mu=10.0, tau=0.5e6),  # below tipping (tau <= p for h = L/2)
          "ratio 20:1": dict(n_base=20, n_block=1)}[case]
    e_u, e_f = errors(bench.stack(str(tmp_path), "s", **kw))
    assert e_u < 1e-8 and e_f < 1e-8, (e_u, e_f)


def test_units_m_and_mm_agree(tmp_path):
    """The same scene in m/kg/s (E, p in Pa) and mm/t/s (MPa): u in mm = 1e3 u in m, forces in N
    equal, to 1e-10 (measured 2e-13): no absolute tolerance in the solve depends on the units."""
    si = bench.stack(str(tmp_path), "si", L=1.0, E_base=2e10, E_block=2e10, p=1e6)
    mm = bench.stack(str(tmp_path), "mm", L=1e3, E_base=2e4, E_block=2e4, p=1.0)
    assert abs(mm[0] / (1e3 * si[0]) - 1) < 1e-10 and abs(mm[1] / si[1] - 1) < 1e-10


@pytest.mark.parametrize("gap, steps", [(0.5, 10), (5.0, 10), (5.0, 1)])
def test_gap_closed_over_load_steps_is_exact(tmp_path, gap, steps):
    """A gap of 1 or 10 element sizes closed by a prescribed displacement: the steps before contact
    only translate the block, so K u and the out-of-balance force are rounding; those steps were
    never accepted (rounding against rtol times rounding, 'no equilibrium after 50 iterations').
    Exact force delta E L / 1.5 (uniaxial, nu = 0) to the multiplier tolerance 1e-8."""
    e_u, e_f = errors(bench.gap_case(str(tmp_path), "g", gap, steps))
    assert e_f < 1e-8, e_f


@pytest.mark.parametrize("gap, nproc", [(0.0, 1), (0.05, 1), (0.0, 2), (0.5, 1)])
def test_partly_supported_block_is_exact(tmp_path, gap, nproc):
    """The block's top pushed down (u_z prescribed), x, y and the rotation about z left free with
    no load along them, frictionless couple: the contact resists none of the three, so G has no
    row for them. The rotation's row came out as rounding (~1e-17: the mode's few-eps share of
    the other rotations times the normals), was kept as a constraint, and gave a rigid rotation
    of ~1e28: exit 1 ("moves by 5.95e28"). Now exact force delta E L / 1.5 to 1e-8 (measured
    6e-13), also on 2 ranks. Gap 0.5 (one element size, the first search pairs 4 of 16 points):
    the dent of the first iteration tilted the interpolated normals by ~1e-5, which then held the
    free translations as a support and slid the block 35 model sizes (exit 1); a mode no point
    resists by 1e-3 of its scale is free (measured 4e-11)."""
    e_u, e_f = errors(bench.gap_case(str(tmp_path), "g", gap, 1, hold=False, nproc=nproc))
    assert e_f < 1e-8, e_f


@pytest.mark.parametrize("tau, block_master, nproc", [(1.2, True, 1), (1.01, False, 1), (1.2, False, 2)])
def test_overturning_block_is_refused(tmp_path, tau, block_master, nproc):
    """A block of height L/2 held only by contact (mu = 10, so friction holds any tau <= 10 p)
    under p and a shear tau on its top: above tau = p the resultant meets the contact plane
    outside the block's footprint (x = L/2 + tau L / 2p), so it overturns and no static state
    exists. It ended in Newton DIVERGED_ITS at every cut and a message blaming the multiplier
    solve; now refused at once, naming the body and where the resultant acts."""
    uz, _, _, _, out, _ = bench.stack(str(tmp_path), "t", mu=10.0, tau=tau * 1e6, block_master=block_master, nproc=nproc)
    assert uz is None, out
    assert "no static equilibrium: body 'block' overturns" in out, out
    assert f"meets that plane at ({0.5 + tau / 2:g}, 0.5, 1.)" in out, out


@pytest.mark.parametrize("block_master", [True, False])
def test_block_just_below_overturning_is_exact(tmp_path, block_master):
    """tau = 0.99 p: the resultant 0.005 L inside the footprint's edge: a static state, the
    friction resultant carries the shear exactly (either side master)."""
    fx, _, fx_ex, _, out, _ = bench.stack(str(tmp_path), "t", mu=10.0, tau=0.99e6, block_master=block_master)
    assert fx is not None, out
    assert abs(fx / fx_ex - 1) < 1e-8, (fx, fx_ex)
