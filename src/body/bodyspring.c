/* Discrete springs and dashpots (Code_Aster's DIS_T, Abaqus' SPRING1/2 and DASHPOT1/2): at a node
   to the ground, or between two nodes of one body, a stiffness and a damping along x, y, z. The
   springs are part of K (so of the static and the Newmark operators, the strain energy, the modes),
   the dashpots of the damping matrix's discrete part Cb (with the absorbing boundaries': the
   Newmark operator's a1 Cb, the damping products and their dissipation). Between two bodies a spring
   would couple their factorizations: the prep refuses it. */
#include <mbc/private/bodyimpl.h>

/* The global rows of the springs' nodes of this body (first DOF; -1 for the ground), the same on
   every rank of the body: rows[2 k], rows[2 k + 1] for its k-th spring end pair, in scene order of
   springs then nodes; *n the pairs. Collective on the body. */
static PetscErrorCode BodySpringRows(MBCBody body, PetscInt *n, PetscInt **rows, PetscReal **k, PetscReal **c)
{
  MBCScene     scene = body->scene;
  PetscSection gsec;
  PetscInt     m = 0;

  PetscFunctionBegin;
  for (PetscInt s = 0; s < scene->nsprings; s++)
    for (PetscInt i = 0; i < scene->springs[s].n; i++) m += scene->springs[s].nodes[2 * i] == body->index;
  *n = m;
  PetscCall(PetscMalloc3(2 * m + 1, rows, 3 * m + 1, k, 3 * m + 1, c));
  PetscCall(DMGetGlobalSection(body->dm, &gsec));
  m = 0;
  for (PetscInt s = 0; s < scene->nsprings; s++) {
    const MBCSpringDesc *sp = &scene->springs[s];
    for (PetscInt i = 0; i < sp->n; i++) {
      if (sp->nodes[2 * i] != body->index) continue;
      for (PetscInt e = 0; e < 2; e++) {
        PetscInt p, off = -1;
        (*rows)[2 * m + e] = -1;
        if (e == 1 && !sp->to) continue;
        PetscCall(MBCBodyNodePoint(body, e ? sp->to[2 * i + 1] : sp->nodes[2 * i + 1], &p));
        if (p >= 0) PetscCall(PetscSectionGetOffset(gsec, p, &off));
        (*rows)[2 * m + e] = off >= 0 ? off : -1; /* owned here */
      }
      for (PetscInt d = 0; d < 3; d++) (*k)[3 * m + d] = sp->k[d], (*c)[3 * m + d] = sp->c[d];
      m++;
    }
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, *rows, 2 * m, MPIU_INT, MPI_MAX, body->comm));
  PetscFunctionReturn(0);
}

/* Adds the springs' (C NULL) or the dashpots' blocks (K NULL) of this body to A, by global rows;
   each pair once, by the rank that owns its first node. A may be a MATPREALLOCATOR (the pattern,
   zeros). The caller assembles A. */
static PetscErrorCode BodySpringBlocks(MBCBody body, PetscBool damping, Mat A)
{
  PetscInt   n, *rows, rstart, rend;
  PetscReal *k, *c;

  PetscFunctionBegin;
  PetscCall(BodySpringRows(body, &n, &rows, &k, &c));
  PetscCall(MatGetOwnershipRange(A, &rstart, &rend));
  for (PetscInt i = 0; i < n; i++) {
    const PetscInt   a = rows[2 * i], b = rows[2 * i + 1];
    const PetscReal *v = damping ? &c[3 * i] : &k[3 * i];
    if (a < rstart || a >= rend) continue;
    for (PetscInt d = 0; d < 3; d++) {
      PetscInt    r[2] = {a + d, b + d};
      PetscScalar blk[4] = {v[d], -v[d], -v[d], v[d]};
      PetscCall(MatSetValues(A, b >= 0 ? 2 : 1, r, b >= 0 ? 2 : 1, r, blk, ADD_VALUES));
    }
  }
  PetscCall(PetscFree3(rows, k, c));
  PetscFunctionReturn(0);
}

/* Does this body have springs or dashpots? */
PetscBool MBCBodyHasSprings(MBCBody body)
{
  for (PetscInt s = 0; s < body->scene->nsprings; s++)
    for (PetscInt i = 0; i < body->scene->springs[s].n; i++)
      if (body->scene->springs[s].nodes[2 * i] == body->index) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* The springs' pattern in the operator's preallocation (MBCBodyCreateOperator). */
PetscErrorCode MBCBodySpringPattern(MBCBody body, Mat pre)
{
  PetscFunctionBegin;
  if (MBCBodyHasSprings(body)) PetscCall(BodySpringBlocks(body, PETSC_FALSE, pre));
  PetscFunctionReturn(0);
}

/* K += the springs (after the elements' assembly); Cb += the dashpots (a dynamic analysis: Cb made
   here if the absorbing boundaries made none), its prescribed rows and columns zeroed as theirs. */
PetscErrorCode MBCBodySpringsSetUp(MBCBody body, PetscBool dynamic)
{
  PetscBool dashpots = PETSC_FALSE;

  PetscFunctionBegin;
  if (!MBCBodyHasSprings(body)) PetscFunctionReturn(0);
  PetscCall(BodySpringBlocks(body, PETSC_FALSE, body->K));
  PetscCall(MatAssemblyBegin(body->K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(body->K, MAT_FINAL_ASSEMBLY));
  for (PetscInt s = 0; s < body->scene->nsprings; s++)
    for (PetscInt d = 0; d < 3; d++) dashpots = (PetscBool)(dashpots || body->scene->springs[s].c[d] > 0);
  if (!dynamic || !dashpots) PetscFunctionReturn(0);
  if (!body->Cb) PetscCall(MBCBodyNodalBlockMatrix(body, &body->Cb));
  PetscCall(MatSetOption(body->Cb, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscCall(BodySpringBlocks(body, PETSC_TRUE, body->Cb));
  PetscCall(MatAssemblyBegin(body->Cb, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(body->Cb, MAT_FINAL_ASSEMBLY));
  PetscCall(MatZeroRowsColumns(body->Cb, body->nbc_free ? body->nbc_free : body->nbc, body->nbc_free ? body->bc_rows_free : body->bc_rows, 0.0, NULL, NULL));
  PetscCall(MatSetOption(body->Cb, MAT_SYMMETRIC, PETSC_TRUE));
  PetscFunctionReturn(0);
}

/* The components the body's ground springs hold somewhere (a static body needs each held). */
void MBCBodySpringHeld(MBCBody body, PetscBool held[3])
{
  for (PetscInt s = 0; s < body->scene->nsprings; s++) {
    const MBCSpringDesc *sp = &body->scene->springs[s];
    if (sp->to) continue;
    for (PetscInt i = 0; i < sp->n; i++)
      if (sp->nodes[2 * i] == body->index)
        for (PetscInt d = 0; d < 3; d++) held[d] = (PetscBool)(held[d] || sp->k[d] > 0);
  }
}
