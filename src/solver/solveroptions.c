/* -help: the options of the parts a scene may not have (contact search, the multiplier solve of either type),
   listed with their defaults, so that -help shows every option the program reads with any scene
   or none. */
#include <mbc/private/solverimpl.h>

PetscErrorCode MBCSolverHelp(MBCSolver s)
{
  MBCContact    c;
  MBCMultiplier m;

  PetscFunctionBegin;
  if (s->scene->ncouples) PetscFunctionReturn(0); /* MBCSolverSetUp reads them */
  PetscCall(MBCContactCreate(s->comm, s->scene, &c));
  PetscCall(MBCContactSetFromOptions(c, ((PetscObject)s)->prefix));
  PetscCall(MBCContactDestroy(&c));
  PetscCall(MBCMultiplierCreate(s->comm, &m)); /* the Newton type lists the pgs type's options too */
  PetscCall(MBCMultiplierSetOptionsPrefix(m, ((PetscObject)s)->prefix));
  PetscCall(MBCMultiplierAppendOptionsPrefix(m, "mbc_"));
  PetscCall(MBCMultiplierSetFromOptions(m));
  PetscCall(MBCMultiplierDestroy(&m));
  PetscFunctionReturn(0);
}
