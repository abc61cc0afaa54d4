/* The couples' master nodes taken out of contact (the scene's `exclude`, as Code_Aster's
   SANS_GROUP_NO): the scene names them by body and vertex (scene order); the contact search knows
   its nodes by body and first global row, so each is looked up where its body owns it. */
#include <mbc/private/solverimpl.h>

/* rows[i]: the first global row of vertex v[i] (scene order) of body b where this rank owns it, else left. */
static PetscErrorCode BodyVertexRows(MBCBody body, PetscInt n, const PetscInt pairs[], PetscInt rows[])
{
  PetscSection    gsec;
  PetscInt        vStart, vEnd, nmine = 0, *key, *idx;
  const PetscInt *vnum;
  PetscInt        bindex;
  DM              bdm;

  PetscFunctionBegin;
  PetscCall(MBCBodyGetIndex(body, &bindex));
  PetscCall(MBCBodyGetDM(body, &bdm));
  PetscCall(MBCBodyGetSceneNumbering(body, &vnum, NULL));
  PetscCall(PetscMalloc2(n + 1, &key, n + 1, &idx));
  for (PetscInt i = 0; i < n; i++)
    if (pairs[2 * i] == bindex) key[nmine] = pairs[2 * i + 1], idx[nmine++] = i;
  PetscCall(PetscSortIntWithArray(nmine, key, idx));
  PetscCall(DMGetGlobalSection(bdm, &gsec));
  PetscCall(DMPlexGetDepthStratum(bdm, 0, &vStart, &vEnd));
  for (PetscInt v = vStart; v < vEnd && nmine; v++) {
    PetscInt at, off;
    PetscCall(PetscFindInt(vnum[v - vStart], nmine, key, &at));
    if (at < 0) continue;
    PetscCall(PetscSectionGetOffset(gsec, v, &off));
    if (off >= 0) rows[idx[at]] = off;
  }
  PetscCall(PetscFree2(key, idx));
  PetscFunctionReturn(0);
}

/* Hands every couple's excluded nodes to the contact search. Collective. */
PetscErrorCode MBCSolverContactExclusions(MBCSolver s)
{
  PetscFunctionBegin;
  for (PetscInt i = 0; i < s->scene->ncouples; i++) {
    const MBCCoupleDesc *cd = &s->scene->couples[i];
    PetscInt            *rows, *pairs;
    if (!cd->nexclude) continue;
    PetscCall(PetscMalloc2(cd->nexclude, &rows, 2 * cd->nexclude, &pairs));
    for (PetscInt j = 0; j < cd->nexclude; j++) rows[j] = -1;
    for (PetscInt b = 0; b < s->nbodies; b++)
      if (s->bodies[b]) PetscCall(BodyVertexRows(s->bodies[b], cd->nexclude, cd->exclude, rows));
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, rows, (PetscMPIInt)cd->nexclude, MPIU_INT, MPI_MAX, s->comm));
    for (PetscInt j = 0; j < cd->nexclude; j++) {
      PetscCheck(rows[j] >= 0, s->comm, PETSC_ERR_PLIB, "Couple k = %" PetscInt_FMT ": excluded vertex %" PetscInt_FMT " of body '%s' was not found in its mesh", cd->k, cd->exclude[2 * j + 1], s->scene->bodies[cd->exclude[2 * j]].name);
      pairs[2 * j] = cd->exclude[2 * j], pairs[2 * j + 1] = rows[j];
    }
    PetscCall(MBCContactSetExcluded(s->contact, i, cd->nexclude, pairs));
    PetscCall(PetscFree2(rows, pairs));
  }
  PetscFunctionReturn(0);
}
