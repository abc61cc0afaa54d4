/* Contact points released at a rebuild of H in a dynamic step whose lambda_n enters through the
   acceleration a_n (Newmark, HHT with alpha 0; docs/design.md, "complementarity on the step's
   mean contact force"). A separated point has z = theta lambda_n+1 + (1 - theta) lambda_n = 0,
   lambda_n+1 = -c lambda_n: the period-2 oscillation of its multiplier stays in a but gives no
   impulse while its H stays. At a rebuild a_n keeps H_old lambda_n while the point goes on with
   H_new lambda_n' (or without it, when the search no longer finds its pair: the bodies parted
   beyond the search distance), and the next step would give the bodies the impulse
   h (1 - gamma) (H_old lambda_n - H_new lambda_n') of that oscillation: two bars parting after an
   impact came apart with 28 times the impact's energy. A point that leaves the set, and one that
   was separated in the step before the rebuild, is released instead: its force H_old lambda_n
   goes on here, per body in the body's layout, as a separated point's with its last H,
   f_n+1 = -c f_n (an impulse of 0 in every step after), and the point, if found again, starts
   from lambda_n' = 0. A point that pressed keeps H_old lambda_n in a_n and lambda_n' (the
   trapezoidal rule on the forces that act; docs/design.md). */
#include <mbc/private/interfaceimpl.h>

/* leaving[k]: old point k (couple order) has no point of the same (couple, master node) among
   the new pairs. Both pair lists are grouped by couple in couple order. */
static PetscErrorCode PointsLeaving(PetscInt ncouples, PetscInt nold, const PetscInt oldpairs[], PetscInt nnew, const PetscInt newpairs[], PetscBool leaving[])
{
  PetscInt *off, *key;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(ncouples + 1, &off));
  PetscCall(PetscMalloc1(nnew + 1, &key));
  for (PetscInt k = 0; k < nnew; k++) {
    off[newpairs[MBC_PAIR_SIZE * k] + 1]++;
    key[k] = newpairs[MBC_PAIR_SIZE * k + 1];
  }
  for (PetscInt i = 0; i < ncouples; i++) {
    off[i + 1] += off[i];
    PetscCall(PetscSortInt(off[i + 1] - off[i], key + off[i]));
  }
  for (PetscInt k = 0; k < nold; k++) {
    const PetscInt i = oldpairs[MBC_PAIR_SIZE * k];
    PetscInt       at;
    PetscCall(PetscFindInt(oldpairs[MBC_PAIR_SIZE * k + 1], off[i + 1] - off[i], key + off[i], &at));
    leaving[k] = (PetscBool)(at < 0);
  }
  PetscCall(PetscFree(off));
  PetscCall(PetscFree(key));
  PetscFunctionReturn(0);
}

/* Before the build for the new pairs (n points) replaces H: adds H_old lambda_n of the points
   released (they leave, or were separated) to released[b] and zeroes their lambda_n in oldlam
   (couple order, what the new points inherit). Does nothing unless ifc->release. Collective. */
PetscErrorCode MBCInterfaceRelease(MBCInterface ifc, PetscInt n, const PetscInt pairs[], PetscReal oldlam[])
{
  const PetscInt nold = ifc->npairs_built;
  PetscBool     *leaving, any = PETSC_FALSE;
  Vec            lam;
  PetscScalar   *a;
  PetscInt       rstart;

  PetscFunctionBegin;
  if (!ifc->release || !nold || !ifc->lamprev) PetscFunctionReturn(0);
  PetscCall(PetscMalloc1(nold, &leaving));
  PetscCall(PointsLeaving(ifc->contact->ncouples, nold, ifc->pairs_built, n, pairs, leaving));
  for (PetscInt k = 0; k < nold; k++) {
    if (!(ifc->rall[ifc->coff[k]] > 0)) leaving[k] = PETSC_TRUE; /* separated: no normal force in the last step */
    if (!leaving[k]) continue;
    any = PETSC_TRUE;
    for (PetscInt i = ifc->coff[k]; i < ifc->coff[k + 1]; i++) oldlam[i] = 0;
  }
  if (!any) { /* the same on every rank: the pairs and r are */
    PetscCall(PetscFree(leaving));
    PetscFunctionReturn(0);
  }
  PetscCall(VecDuplicate(ifc->lamprev, &lam));
  PetscCall(VecCopy(ifc->lamprev, lam));
  PetscCall(VecGetOwnershipRange(lam, &rstart, NULL));
  PetscCall(VecGetArray(lam, &a));
  for (PetscInt p = ifc->pfirst; p < ifc->plast; p++)
    if (!leaving[ifc->order[p]])
      for (PetscInt i = ifc->poff[p]; i < ifc->poff[p + 1]; i++) a[i - rstart] = 0;
  PetscCall(VecRestoreArray(lam, &a));
  PetscCall(MBCInterfaceToBodies(ifc, lam)); /* lam[b] goes with the old H */
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    if (!ifc->H[b]) continue;
    if (!ifc->released[b]) {
      Vec u;
      PetscCall(MBCBodyGetDisplacement(ifc->bodies[b], &u));
      PetscCall(VecDuplicate(u, &ifc->released[b]));
      PetscCall(VecZeroEntries(ifc->released[b]));
    }
    PetscCall(MatMultAdd(ifc->H[b], ifc->lam[b], ifc->released[b], ifc->released[b]));
  }
  PetscCall(VecDestroy(&lam));
  PetscCall(PetscFree(leaving));
  PetscFunctionReturn(0);
}

/* f_n+1 = w f with w = -c: the released points' force on body b at the end of the step, their
   mean force over it 0, which the step adds to the body's right side (f NULL: none). On the body's
   ranks. */
PetscErrorCode MBCInterfaceGetReleasedStepForce(MBCInterface ifc, PetscInt b, PetscReal *w, Vec *f)
{
  PetscFunctionBegin;
  *w = -ifc->carry;
  *f = ifc->release ? ifc->released[b] : NULL;
  PetscFunctionReturn(0);
}

/* After a step: f_n+1 = -c f_n becomes the force the acceleration holds. */
PetscErrorCode MBCInterfaceReleasedStep(MBCInterface ifc)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; ifc->release && b < ifc->nbodies; b++)
    if (ifc->released[b]) PetscCall(VecScale(ifc->released[b], -ifc->carry));
  PetscFunctionReturn(0);
}

/* Body b's released force, for the checkpoint (created at 0 where none is). On the body's ranks. */
PetscErrorCode MBCInterfaceGetReleasedForce(MBCInterface ifc, PetscInt b, Vec *f)
{
  PetscFunctionBegin;
  if (!ifc->released[b]) {
    Vec u;
    PetscCall(MBCBodyGetDisplacement(ifc->bodies[b], &u));
    PetscCall(VecDuplicate(u, &ifc->released[b]));
    PetscCall(VecZeroEntries(ifc->released[b]));
  }
  *f = ifc->released[b];
  PetscFunctionReturn(0);
}

/* No released force (a new analysis or stage: its acceleration comes from the forces that act). */
PetscErrorCode MBCInterfaceReleasedClear(MBCInterface ifc)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; b < ifc->nbodies; b++) PetscCall(VecDestroy(&ifc->released[b]));
  PetscFunctionReturn(0);
}
