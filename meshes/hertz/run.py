#!/usr/bin/python3
"""make run: the paper's Hertz example (two parallel cylinders, static, a quick mesh level)
against Hertz theory and the paper's results.

  meshes/hertz/run.py [--hc 0.01] [--dynamic]
"""
import argparse
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import build  # noqa: E402
import report  # noqa: E402

SOLVER = os.path.join(os.environ.get("MBC_BUILD_DIR", os.path.join(ROOT, "build")), "mbcontact")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--hc", type=float, default=0.01, help="element edge at the contact [mm] (default 0.01: b / 19)")
    ap.add_argument("--dynamic", action="store_true", help="the paper's route: Newmark, dt 0.01 s to 3 s")
    a = ap.parse_args()
    work = os.path.join(ROOT, "build", "run", "hertz")
    analysis = "dynamic" if a.dynamic else "static"
    h5 = build.build(work, a.hc, analysis=analysis)
    t0 = time.perf_counter()
    subprocess.run([SOLVER, "-scene", h5], check=True)
    elapsed = time.perf_counter() - t0
    res = report.cylinder_results(os.path.join(work, "hertz_result"))
    report.print_report(res, f"Hertz: two parallel cylinders ({analysis}, {a.hc} mm elements at the contact)")
    print(f"\nrun time {elapsed:.1f} s; contact points per row {res['points']}, loaded {res['loaded']}; "
          f"results in {work}/hertz_result.xmf (ParaView)")
    print(report.summary(res))


if __name__ == "__main__":
    main()
