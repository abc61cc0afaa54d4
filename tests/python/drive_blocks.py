"""The two-block example driven from Python (test_python.py runs it under mpirun): options
through PETSc.Options, step() to the end with a monitor, then what the binding exposes,
printed as 'key value' lines by rank 0."""
import sys

from petsc4py import PETSc

import mbcontact

scene_file, output = sys.argv[1], sys.argv[2]
opts = PETSc.Options()
for k, v in [("mbc_analysis", "static"), ("mbc_dt", "1"), ("mbc_final_time", "2"), ("mbc_output", output)]:
    opts[k] = v
comm = PETSc.COMM_WORLD
scene = mbcontact.Scene().load(scene_file)
solver = mbcontact.Solver().create()
solver.setScene(scene)
del scene  # the solver holds its own reference
solver.setFromOptions()
seen = []
solver.setMonitor(lambda s, step, t: seen.append((step, t)))
solver.setUp()
u = {}
for name in solver.getBodyNames():
    body = solver.getBody(name)
    if body is not None:  # on this rank
        u[name] = body.getDisplacement()
while not solver.done:
    solver.step()
mpi = comm.tompi4py()
out = {"steps": ",".join(f"{k}:{t:g}" for k, t in seen), "nbodies": solver.getNumBodies(),
       "comm_size": solver.getComm().getSize()}
for name in ("block1", "block2"):
    body = solver.getBody(name)
    umin = body.getDisplacement().min()[1] if body is not None and body.getDisplacement().getComm().getRank() == 0 else None
    # the Vec got before the steps is the solver's: it moved with them
    same = body is None or body.getDisplacement().min()[1] == u[name].min()[1]
    out[f"{name}_umin"] = next(v for v in mpi.allgather(umin) if v is not None)
    out[f"{name}_same"] = all(mpi.allgather(same))
lam = solver.getMultipliers().getArray()
out["normal_force"] = mpi.allreduce(float(lam[0::3].sum()))
cp = solver.getContactPoints()
out["points"] = len(cp["pressure"])
out["stick"] = int((cp["state"] == 1).sum())
out["pressure_mean"] = float(cp["pressure"].mean())
try:
    solver.step()
except PETSc.Error as e:
    out["error_after_end"] = str(e)
if comm.getRank() == 0:
    for k, v in out.items():
        print(k, v)
