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
