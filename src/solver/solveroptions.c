/* -help: the options of the parts a scene may not have (contact search, projected Gauss-Seidel),
   listed with their defaults, so that -help shows every option the program reads with any scene
   or none. */
#include <mbc/private/solverimpl.h>

PetscErrorCode MBCSolverHelp(MBCSolver s)
{
  MBCContact c;
  MBCPGS     pgs;

  PetscFunctionBegin;
  if (s->scene->ncouples) PetscFunctionReturn(0); /* MBCSolverSetUp reads them */
  PetscCall(MBCContactCreate(s->comm, s->scene, &c));
  PetscCall(MBCContactSetFromOptions(c));
  PetscCall(MBCContactDestroy(&c));
  PetscCall(PetscMemzero(&pgs, sizeof(pgs)));
  PetscCall(MBCPGSSetFromOptions(&pgs));
  PetscCall(MBCPGSReset(&pgs));
  PetscFunctionReturn(0);
}
