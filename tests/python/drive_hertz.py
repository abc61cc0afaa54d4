"""The Hertz cylinders driven from Python (test_python.py runs it under mpirun): solve(), then the
contact points the binding returns, printed as 'key value' lines by rank 0."""
import sys

import numpy as np
from petsc4py import PETSc

import mbcontact

scene_file, output = sys.argv[1], sys.argv[2]
PETSc.Options()["mbc_output"] = output
solver = mbcontact.Solver().create()
solver.setScene(mbcontact.Scene().load(scene_file))
solver.setFromOptions()
solver.solve()
pts = solver.getContactPoints()
inside = pts["state"] > 0
if PETSc.COMM_WORLD.getRank() == 0:
    print("points", len(pts["pressure"]))
    print("closed", int(inside.sum()))
    print("p_max", float(pts["pressure"].max()))
    print("p_sum", float(pts["pressure"][inside].sum()))
