"""Two solvers in one script, set apart by options prefixes a_ and b_ (test_python.py): each
reads its own multiplier type, contact search and body options; prints 'key value' lines."""
import sys

from petsc4py import PETSc

import mbcontact

scene_file, outdir = sys.argv[1], sys.argv[2]
opts = PETSc.Options()
for p, mtype in (("a_", "pgs"), ("b_", "newton")):
    opts[p + "mbc_multiplier_type"] = mtype
    opts[p + "mbc_monitor"] = None
    opts[p + "mbc_final_time"] = "0.02"
    opts[p + "mbc_output"] = f"{outdir}/{p}run"
opts["a_mbc_contact_view"] = None  # the search report of a only
opts["b_body_ksp_type"] = "preonly"  # copied to b's bodies only: -b_body_<name>_ksp_type
for p in ("a_", "b_"):
    solver = mbcontact.Solver().create()
    solver.setScene(mbcontact.Scene().load(scene_file))
    solver.setOptionsPrefix(p)
    solver.setFromOptions()
    print("begin", p, flush=True)
    solver.solve()
    print("end", p, flush=True)
    for name in solver.getBodyNames():
        body = solver.getBody(name)
        if body is not None:
            print(p, name, "ksp_prefix", body.getKSP().getOptionsPrefix())
    solver.destroy()
print("b_body_block1_ksp_type", opts.getString("b_body_block1_ksp_type", ""))
print("a_body_block1_ksp_type", opts.getString("a_body_block1_ksp_type", ""))
