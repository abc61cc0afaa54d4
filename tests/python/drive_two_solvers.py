"""Two solvers on one Scene object in one process (test_python.py): a_ static, b_ dynamic with a
lumped mass, set from options in the order b, a, then stepped in turn. Each must give the answer
it gives alone: the scene is read-only to them."""
import sys

from petsc4py import PETSc

import mbcontact

scene_file, outdir = sys.argv[1], sys.argv[2]
opts = PETSc.Options()
settings = {"a_": {"mbc_analysis": "static", "mbc_dt": "0.5", "mbc_final_time": "1"},
            "b_": {"mbc_analysis": "dynamic", "mbc_mass": "lumped", "mbc_dt": "0.01", "mbc_final_time": "0.05"}}
for p, kv in settings.items():
    for k, v in kv.items():
        opts[p + k] = v
    opts[p + "mbc_output"] = f"{outdir}/{p}shared"
scene = mbcontact.Scene().load(scene_file)
solvers = {}
for p in ("a_", "b_"):
    solvers[p] = mbcontact.Solver().create()
    solvers[p].setScene(scene)
    solvers[p].setOptionsPrefix(p)
for p in ("b_", "a_"):  # the static one last: it used to leave the scene static under b
    solvers[p].setFromOptions()
while not all(s.done for s in solvers.values()):
    for s in solvers.values():
        if not s.done:
            s.step()
for s in solvers.values():
    s.destroy()
print("done")
