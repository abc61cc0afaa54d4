"""A body's lumped nodal blocks through the binding (test_seismic.py runs it): after setUp, the
x-x, z-z and x-z entries of M (or of the dashpots Cb) at every vertex, with the vertex's
coordinates, into an .npz (one rank)."""
import sys

import numpy as np
from petsc4py import PETSc

import mbcontact

scene_file, body_name, which, out = sys.argv[1:5]
solver = mbcontact.Solver().create()
solver.setScene(mbcontact.Scene().load(scene_file))
solver.setFromOptions()
solver.setUp()
body = solver.getBody(body_name)
K, M, Cb = body.getOperators()
A = {"M": M, "Cb": Cb}[which]
dm = body.getDM()
x = dm.getCoordinatesLocal().getArray().reshape(-1, 3)
n = x.shape[0]
blocks = np.zeros((n, 3, 3))
for i in range(n):  # one rank: local = global rows
    for a in range(3):
        for b in range(3):
            blocks[i, a, b] = A.getValue(3 * i + a, 3 * i + b)
np.savez(out, x=x, blocks=blocks, none=np.array([Cb is None]))
