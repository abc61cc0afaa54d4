"""The short fixed-seed fuzzing run (tests/fuzz/fuzz.py): mutants of scene .h5 files, YAML scenes
and FCLIB files must each be rejected with a message or accepted with finite, bounded results;
no crash, no hang. The long run is `make fuzz N=10000` (figures in docs/validation.md)."""
import os
import sys

from conftest import ROOT

sys.path.insert(0, os.path.join(ROOT, "tests", "fuzz"))
import fuzz  # noqa: E402


def test_fuzz_short_run(capsys):
    status = fuzz.main(["-n", "25", "--seed", "13", "-j", "2", "--timeout", "60"])
    out = capsys.readouterr().out
    assert status == 0, out
    # the mutators must reach the solver's checks, not only the HDF5 open
    assert out.count("rejected") == 3 and " 0 crash, 0 hang, 0 garbage" in out, out


def test_fclib_mutants_whose_newton_iteration_meets_a_nan(capsys):
    """Two FCLIB mutants of the long run (seed 5: W's values shuffled) where the Newton iteration
    meets a NaN: the solver returned that NaN iterate (merit -nan, exit 2: 'not converged' with a
    non-finite answer), since its 'return the best iterate' test was best < merit, false for a
    NaN. Now the best finite iterate comes back (merit 1.04e-4, DIVERGED_NANORINF, exit 2)."""
    for i in ("47", "292"):
        status = fuzz.main(["--seed", "5", "--kind", "fclib", "--only", i])
        out = capsys.readouterr().out
        assert status == 0 and "accepted (exit 2" in out, out
