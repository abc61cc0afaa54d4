"""Dynamic cases of bench/extremes_dynamic.py (docs/stability.md), one per category and
both ends of the time-step sweep, against their references. About 25 s in all (nice 10, shared
machine)."""
import numpy as np
import pytest

from conftest import load_script, result
from mbcontact.results import read_csv

bench = load_script("bench/extremes_dynamic.py", "bench_extremes_dynamic")


@pytest.mark.parametrize("dt", [1.0, 1e-4])
def test_timestep_extremes_keep_the_trapezoidal_error(tmp_path, dt):
    """The block sliding under a ramped push (rigid Coulomb slide x = j T^3 / 6 = 1.635 m at
    T = 1 s) in one step of 1 s, and in 10 000 steps of 1e-4 s (1e3 times the elastic periods
    and 1e-1 of them). The trapezoidal rule integrates this motion to x = j T^3 / 6 + j T dt^2 / 12
    exactly, so the relative error must be dt^2 / 2 (0.5 and 5e-9) up to the elastic block's
    departure from the rigid one (measured below 1e-6 at both; asserted 1e-5): the
    accuracy follows the order-2 law, nothing else. Every multiplier solve converges, no step is
    cut, and the mechanical energy plus what friction took never rises above 0 by more than
    1e-6 of the reference kinetic energy (measured 0 and 6e-10)."""
    r = bench.slide_case(str(tmp_path), dt)
    print(f"\ndt {dt:g}: error {r['error']:.3e} (expected {r['expected']:.3e}), drift {r['drift']:.2e}, "
          f"{r['mult_its']} multiplier iterations, {r['wall']:.1f} s")
    assert r["reasons"] == ["CONVERGED_RTOL"] and r["cuts"] == 0, (r["reasons"], r["note"])
    assert abs(r["error"] - dt**2 / 2) < 1e-5, (r["error"], dt**2 / 2)
    assert r["drift"] < 1e-6, r["drift"]
    assert r["ok"]


@pytest.mark.parametrize("keep", [False, True], ids=["default", "keep_penetration"])
def test_hundred_undamped_bounces_gain_no_energy(tmp_path, keep):
    """Regression test of the gap to a warped slave quad (MBCCoupleProjectOnFace): a stiff block
    (one cell, 1000 kg) dropped 10 um onto a light elastic pad (one cell, 2 kg, E 4e9),
    frictionless, undamped, trapezoidal, dt = 1e-4 s, for 100 periods of the first bounce
    (0.48 s, 2393 steps). The gap was measured to the slave face's mean plane while H moved its
    corners with the bilinear weights: the pad's top face twisting into a saddle changed the gap
    H^T du predicted by the warp, each step closed the difference, the contact forces did work,
    and the mechanical energy rose to 2600 times the impact energy K_i. Now it never exceeds 0 by
    more than 1e-6 K_i (measured 4e-15), with the default step and with
    -mbc_contact_keep_penetration (a step starts from max(gap, 0)); the block lands more than 100
    times (measured 116; each landing loses ~1 %: the pad's top nodes are stopped); the pad's
    deepest compression in the first contact is the rigid block's on the pad's spring within 1e-2
    (measured 1.8e-3: the steps sample the peak, (w dt)^2 / 8 = 5e-3, and the pad's mass is 2e-3
    of the block's); the penetration left at a corner is below 1e-6 of the drop (measured 1e-13
    m; 4.5e-5 m before). The energy CSV's total (kinetic + strain - work + the dissipations)
    closes within 1e-9 K_i, and the normal contact's share never decreases."""
    r = bench.bounce_case(str(tmp_path), 100, keep=keep)
    print(f"\n100 periods{' keep' if keep else ''}: drift {r['drift']:.2e} K_i, lost {r['loss']:.3f} K_i, {r['impacts']} impacts, "
          f"peak error {r['error']:.2e}, penetration {r['penetration']:.2e} m, {r['wall']:.1f} s")
    assert r["reasons"] == ["CONVERGED_RTOL"], (r["reasons"], r["note"])
    assert r["drift"] < 1e-6, r["drift"]
    assert r["impacts"] > 100, r["impacts"]
    assert r["error"] < 1e-2, r["error"]
    assert r["penetration"] < 1e-6 * bench.DELTA, r["penetration"]
    assert r["ok"]
    en = read_csv(result(tmp_path / f"bounce_100{'_keep' if keep else ''}.h5", "_energy.csv"))
    k_i = bench.bounce_reference()[0]
    assert np.abs(en["total"]).max() < 1e-9 * k_i, np.abs(en["total"]).max()
    assert np.diff(en["contact_dissipation"]).min() > -1e-9 * k_i
