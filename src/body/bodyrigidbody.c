/* A rigid body (the scene's `rigid`): six DOFs q, the translation of its reference point x_r and a
   small rotation about it, seen by everything else through its nodes, u = T q with T's columns e_d
   and e_k x (x - x_r) at every node. Its mesh (volume cells, or a surface: Code_Aster's rigid
   contact surface) gives the nodes the contact search, the loads and the output use; the solves are
   the projected ones, x = T_f S^-1 T_f^T b over the free components f of q (S = T^T (aK K + aM M) T,
   K = 0: a static rigid body's free components are FETI's rigid modes, its K^+ = 0), plus the
   prescribed motion T q_p. Its mass about x_r, M_r, comes from its cells and density, or is given
   (mass, inertia); the nodal mass is M = P M_r P^T with P = T (T^T T)^-1 (a MATSHELL), so T^T M T = M_r
   and the Newmark updates, kinetic energy and inertial loads are those of the six DOFs. */
#include <mbc/private/bodyimpl.h>
#include <petscblaslapack.h>

typedef struct {
  MBCBody   body;
  PetscReal Sinv[36]; /* S^-1 on the free components, 0 elsewhere */
} RigidPC;

/* y = T c (c: 6 values) */
static PetscErrorCode RigidSpread(MBCBody body, const PetscReal c[6], Vec y)
{
  PetscFunctionBegin;
  PetscCall(VecZeroEntries(y));
  for (PetscInt j = 0; j < 6; j++)
    if (c[j] != 0) PetscCall(VecAXPY(y, c[j], body->Trig[j]));
  PetscFunctionReturn(0);
}

/* c = T^T x */
static PetscErrorCode RigidGather(MBCBody body, Vec x, PetscReal c[6])
{
  PetscScalar d[6];

  PetscFunctionBegin;
  PetscCall(VecMDot(x, 6, body->Trig, d));
  for (PetscInt j = 0; j < 6; j++) c[j] = PetscRealPart(d[j]);
  PetscFunctionReturn(0);
}

static void Mult6(const PetscReal A[36], const PetscReal x[6], PetscReal y[6])
{
  for (PetscInt i = 0; i < 6; i++) {
    y[i] = 0;
    for (PetscInt j = 0; j < 6; j++) y[i] += A[6 * i + j] * x[j];
  }
}

/* Inverse of the symmetric positive definite n x n block of A on the components idx (in place into
   Ai, 6 x 6, zero elsewhere); PETSC_FALSE if that block is singular. */
static PetscBool Invert6(const PetscReal A[36], PetscInt n, const PetscInt idx[], PetscReal Ai[36])
{
  PetscScalar  a[36], work[64];
  PetscBLASInt nn = (PetscBLASInt)n, ipiv[6], lwork = 64, info;

  for (PetscInt i = 0; i < 36; i++) Ai[i] = 0;
  if (!n) return PETSC_TRUE;
  for (PetscInt i = 0; i < n; i++)
    for (PetscInt j = 0; j < n; j++) a[i * n + j] = A[6 * idx[i] + idx[j]];
  {
    PetscReal scale = 0;
    for (PetscInt i = 0; i < n; i++) scale = PetscMax(scale, PetscAbsScalar(a[i * n + i]));
    if (!(scale > 0)) return PETSC_FALSE;
    LAPACKgetrf_(&nn, &nn, a, &nn, ipiv, &info);
    if (info) return PETSC_FALSE;
    for (PetscInt i = 0; i < n; i++)
      if (PetscAbsScalar(a[i * n + i]) < 1e-12 * scale) return PETSC_FALSE;
    LAPACKgetri_(&nn, a, &nn, ipiv, work, &lwork, &info);
    if (info) return PETSC_FALSE;
  }
  for (PetscInt i = 0; i < n; i++)
    for (PetscInt j = 0; j < n; j++) Ai[6 * idx[i] + idx[j]] = PetscRealPart(a[i * n + j]);
  return PETSC_TRUE;
}

static PetscErrorCode RigidPCApply(PC pc, Vec x, Vec y)
{
  RigidPC  *ctx;
  PetscReal c[6], q[6];

  PetscFunctionBegin;
  PetscCall(PCShellGetContext(pc, &ctx));
  PetscCall(RigidGather(ctx->body, x, c));
  Mult6(ctx->Sinv, c, q);
  PetscCall(RigidSpread(ctx->body, q, y));
  PetscFunctionReturn(0);
}

static PetscErrorCode RigidPCDestroy(PC pc)
{
  RigidPC *ctx;

  PetscFunctionBegin;
  PetscCall(PCShellGetContext(pc, &ctx));
  PetscCall(PetscFree(ctx));
  PetscFunctionReturn(0);
}

/* y = M x = P M_r P^T x, P = T (T^T T)^-1 */
static PetscErrorCode RigidMassMult(Mat M, Vec x, Vec y)
{
  MBCBody   body;
  PetscReal c[6], p[6], m[6];

  PetscFunctionBegin;
  PetscCall(MatShellGetContext(M, &body));
  PetscCall(RigidGather(body, x, c));
  Mult6(body->TtTinv, c, p);
  Mult6(body->Mr, p, m);
  Mult6(body->TtTinv, m, p);
  PetscCall(RigidSpread(body, p, y));
  PetscFunctionReturn(0);
}

/* The components of q the scene prescribes (dirichlet entries naming the body, the last wins). */
static void RigidPrescribedEntries(MBCBody body, PetscInt entry[6])
{
  for (PetscInt d = 0; d < 6; d++) entry[d] = -1;
  for (PetscInt e = 0; e < body->scene->ndirichlet; e++)
    if (body->scene->dirichlet[e].body == body->index) entry[body->scene->dirichlet[e].component] = e;
}

/* T, T^T T and its inverse, K (zero), M_r and the shell M. Collective on the body. */
PetscErrorCode MBCBodyRigidSetUp(MBCBody body, PetscBool dynamic)
{
  const MBCBodyDesc *d = &body->desc;
  Vec                coords, loc;
  const PetscScalar *x;
  PetscSection       lsec;
  PetscInt           pStart, pEnd, m, n, free = 0, entry[6];
  PetscReal          Munit[36] = {0}, TtT[36];

  PetscFunctionBegin;
  PetscCall(DMGetLocalSection(body->dm, &lsec));
  PetscCall(DMGetCoordinatesLocal(body->dm, &coords));
  PetscCall(DMPlexGetChart(body->dm, &pStart, &pEnd));
  PetscCall(DMGetLocalVector(body->dm, &loc));
  PetscCall(VecGetArrayRead(coords, &x));
  for (PetscInt j = 0; j < 6; j++) {
    PetscScalar *l;
    PetscCall(VecZeroEntries(loc));
    PetscCall(VecGetArray(loc, &l));
    for (PetscInt p = pStart; p < pEnd; p++) {
      PetscInt  off, dof;
      PetscReal X[3];
      PetscCall(PetscSectionGetDof(lsec, p, &dof));
      if (dof < 3) continue;
      PetscCall(PetscSectionGetOffset(lsec, p, &off));
      PetscCall(MBCBodyPointCoordinates(body, p, x, X));
      for (PetscInt c = 0; c < 3; c++) X[c] -= d->reference[c];
      if (j < 3) l[off + j] = 1;
      else { /* e_k x X */
        const PetscInt k = j - 3, a = (k + 1) % 3, b = (k + 2) % 3;
        l[off + a] = -X[b];
        l[off + b] = X[a];
      }
    }
    PetscCall(VecRestoreArray(loc, &l));
    PetscCall(DMCreateGlobalVector(body->dm, &body->Trig[j]));
    PetscCall(DMLocalToGlobal(body->dm, loc, INSERT_VALUES, body->Trig[j]));
  }
  PetscCall(VecRestoreArrayRead(coords, &x));
  PetscCall(DMRestoreLocalVector(body->dm, &loc));
  for (PetscInt j = 0; j < 6; j++) {
    PetscScalar dots[6];
    PetscCall(VecMDot(body->Trig[j], 6, body->Trig, dots));
    for (PetscInt k = 0; k < 6; k++) TtT[6 * j + k] = PetscRealPart(dots[k]);
  }
  {
    const PetscInt all[6] = {0, 1, 2, 3, 4, 5};
    PetscCheck(Invert6(TtT, 6, all, body->TtTinv), body->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: rigid body '%s': its nodes do not fix a rotation (all on one line?)", body->scene->filename, body->name);
  }
  /* K = 0 (no element); the nodal mass of unit density from the cells (a volume) */
  PetscCall(DMSetMatrixPreallocateSkip(body->dm, PETSC_TRUE));
  PetscCall(DMCreateMatrix(body->dm, &body->K));
  PetscCall(DMSetMatrixPreallocateSkip(body->dm, PETSC_FALSE));
  PetscCall(MatSetUp(body->K));
  PetscCall(MatAssemblyBegin(body->K, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(body->K, MAT_FINAL_ASSEMBLY));
  if (!body->surface) {
    Mat       Me;
    Vec       y;
    PetscReal rho = body->desc.density;
    PetscCall(MBCBodyCreateOperator(body, &Me));
    body->desc.density = 1.0;
    {
      Mat K0;
      PetscCall(MatDuplicate(Me, MAT_DO_NOT_COPY_VALUES, &K0));
      PetscCall(MBCBodyAssembleElasticity(body, K0, Me));
      PetscCall(MatDestroy(&K0));
    }
    body->desc.density = rho;
    PetscCall(VecDuplicate(body->Trig[0], &y));
    for (PetscInt j = 0; j < 6; j++) {
      PetscScalar dots[6];
      PetscCall(MatMult(Me, body->Trig[j], y));
      PetscCall(VecMDot(y, 6, body->Trig, dots));
      for (PetscInt k = 0; k < 6; k++) Munit[6 * j + k] = PetscRealPart(dots[k]);
    }
    PetscCall(VecDestroy(&y));
    PetscCall(MatDestroy(&Me));
  }
  /* M_r: given mass (and inertia about the reference), else the cells' with the density */
  if (d->rigid_mass > 0) {
    PetscBool inertia = PETSC_FALSE;
    for (PetscInt i = 0; i < 9; i++) inertia = (PetscBool)(inertia || d->rigid_inertia[i] != 0);
    for (PetscInt i = 0; i < 36; i++) body->Mr[i] = 0;
    if (!inertia && Munit[0] > 0) /* the cells' distribution scaled to the mass: the coupling of translation and rotation about a reference off the mass centre kept */
      for (PetscInt i = 0; i < 36; i++) body->Mr[i] = d->rigid_mass / Munit[0] * Munit[i];
    else { /* given inertia: about the reference, taken as the mass centre */
      for (PetscInt i = 0; i < 3; i++) body->Mr[7 * i] = d->rigid_mass;
      for (PetscInt i = 0; i < 3; i++)
        for (PetscInt j = 0; j < 3; j++) body->Mr[6 * (3 + i) + 3 + j] = d->rigid_inertia[3 * i + j];
    }
  } else
    for (PetscInt i = 0; i < 36; i++) body->Mr[i] = d->density * Munit[i];
  RigidPrescribedEntries(body, entry);
  for (PetscInt c = 0; c < 6; c++) free += entry[c] < 0;
  if (dynamic && free) { /* the free components need inertia */
    PetscInt  idx[6], nf = 0;
    PetscReal Si[36];
    for (PetscInt c = 0; c < 6; c++)
      if (entry[c] < 0) idx[nf++] = c;
    PetscCheck(Invert6(body->Mr, nf, idx, Si), body->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: rigid body '%s' moves freely in %" PetscInt_FMT " of its components but has no mass there (a surface needs `mass` and `inertia`, a volume a density or `mass`); prescribe its motion (dirichlet: {body: %s}) or give it a mass", body->scene->filename, body->name, nf, body->name);
  }
  PetscCall(VecGetLocalSize(body->Trig[0], &m));
  PetscCall(VecGetSize(body->Trig[0], &n));
  if (dynamic) {
    PetscCall(MatCreateShell(body->comm, m, m, n, n, body, &body->M));
    PetscCall(MatShellSetOperation(body->M, MATOP_MULT, (void (*)(void))RigidMassMult));
    PetscCall(MatShellSetOperation(body->M, MATOP_MULT_TRANSPOSE, (void (*)(void))RigidMassMult));
  }
  PetscFunctionReturn(0);
}

/* The rigid body's factor of aK K + aM M (the projected solve; A: K, the zero matrix). */
PetscErrorCode MBCBodyRigidFactor(MBCBody body, PetscReal aK, PetscReal aM, KSP *ksp, Mat *A)
{
  RigidPC  *ctx;
  PC        pc;
  PetscInt  entry[6], idx[6], nf = 0;
  PetscReal S[36];

  PetscFunctionBegin;
  RigidPrescribedEntries(body, entry);
  for (PetscInt c = 0; c < 6; c++)
    if (entry[c] < 0) idx[nf++] = c;
  for (PetscInt i = 0; i < 36; i++) S[i] = aM * body->Mr[i]; /* T^T K T = 0 */
  PetscCall(PetscNew(&ctx));
  ctx->body = body;
  if (aM != 0) PetscCheck(Invert6(S, nf, idx, ctx->Sinv), body->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: rigid body '%s' has no mass in a component it moves freely in", body->scene->filename, body->name);
  PetscCall(PetscObjectReference((PetscObject)body->K));
  *A = body->K;
  PetscCall(KSPCreate(body->comm, ksp));
  PetscCall(KSPSetOperators(*ksp, body->K, body->K));
  PetscCall(KSPSetType(*ksp, KSPPREONLY));
  PetscCall(KSPGetPC(*ksp, &pc));
  PetscCall(PCSetType(pc, PCSHELL));
  PetscCall(PCShellSetContext(pc, ctx));
  PetscCall(PCShellSetApply(pc, RigidPCApply));
  PetscCall(PCShellSetDestroy(pc, RigidPCDestroy));
  PetscCall(PCShellSetName(pc, "rigid body: the projection onto its free components"));
  PetscCall(KSPSetUp(*ksp));
  PetscFunctionReturn(0);
}

/* q = (T^T T)^-1 T^T u: the rigid motion of the nodal displacement u */
PetscErrorCode MBCBodyRigidMotion(MBCBody body, Vec u, PetscReal q[6])
{
  PetscReal c[6];

  PetscFunctionBegin;
  PetscCall(RigidGather(body, u, c));
  Mult6(body->TtTinv, c, q);
  PetscFunctionReturn(0);
}

/* g = T (q_p(t) - q_p(u)) on the prescribed components (increment) or T q_p(t) (u NULL). */
PetscErrorCode MBCBodyRigidPrescribed(MBCBody body, PetscReal t, Vec u, Vec g)
{
  PetscInt  entry[6];
  PetscReal q[6] = {0, 0, 0, 0, 0, 0}, now[6] = {0, 0, 0, 0, 0, 0};

  PetscFunctionBegin;
  RigidPrescribedEntries(body, entry);
  if (u) PetscCall(MBCBodyRigidMotion(body, u, now));
  for (PetscInt c = 0; c < 6; c++) {
    const MBCDirichletDesc *d = entry[c] >= 0 ? &body->scene->dirichlet[entry[c]] : NULL;
    PetscReal               f;
    if (!d) continue;
    PetscCall(MBCTimeFactor(body->scene, d->time, d->time_function, t, &f));
    q[c] = d->value * f - now[c];
  }
  PetscCall(RigidSpread(body, q, g));
  PetscFunctionReturn(0);
}

/* x = g + T_f S^-1 T_f^T (rhs - aK K g - aM M g): the rigid counterpart of a constrained solve. */
PetscErrorCode MBCBodyRigidSolve(MBCBody body, KSP ksp, PetscReal aM, Vec g, Vec rhs, Vec x)
{
  PetscFunctionBegin;
  if (g && aM != 0) {
    PetscCall(MatMult(body->M, g, body->work));
    PetscCall(VecAXPY(rhs, -aM, body->work));
  }
  PetscCall(KSPSolve(ksp, rhs, x));
  if (g) PetscCall(VecAXPY(x, 1.0, g));
  PetscFunctionReturn(0);
}

/* A static rigid body's free components as FETI's rigid modes (orthonormal), K^+ = 0: nothing held. */
PetscErrorCode MBCBodyRigidFreeModes(MBCBody body)
{
  PetscInt entry[6], k = 0;

  PetscFunctionBegin;
  RigidPrescribedEntries(body, entry);
  for (PetscInt c = 0; c < 6; c++) k += entry[c] < 0;
  body->nrigid = k;
  body->nfix   = 0;
  if (!k) PetscFunctionReturn(0);
  PetscCall(PetscMalloc1(k, &body->rigid));
  PetscCall(PetscMalloc3(k, &body->fix_rows, k, &body->erigid, k, &body->frigid));
  for (PetscInt c = 0, j = 0; c < 6; c++) {
    if (entry[c] >= 0) continue;
    PetscCall(VecDuplicate(body->Trig[c], &body->rigid[j]));
    PetscCall(VecCopy(body->Trig[c], body->rigid[j]));
    for (PetscInt i = 0; i < j; i++) { /* Gram-Schmidt against the ones before */
      PetscScalar dot;
      PetscCall(VecDot(body->rigid[j], body->rigid[i], &dot));
      PetscCall(VecAXPY(body->rigid[j], -dot, body->rigid[i]));
    }
    PetscCall(VecNormalize(body->rigid[j], NULL));
    j++;
  }
  PetscFunctionReturn(0);
}

/* F = P M_r (g, 0): gravity g on a rigid body (its mass about the reference, the moment of an
   off-centre centre of mass included). */
PetscErrorCode MBCBodyRigidGravity(MBCBody body, const PetscReal g[3], Vec F)
{
  PetscReal a[6] = {g[0], g[1], g[2], 0, 0, 0}, f[6], p[6];

  PetscFunctionBegin;
  Mult6(body->Mr, a, f);
  Mult6(body->TtTinv, f, p);
  PetscCall(RigidSpread(body, p, F));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyRigidDestroy(MBCBody body)
{
  PetscFunctionBegin;
  for (PetscInt j = 0; j < 6; j++) PetscCall(VecDestroy(&body->Trig[j]));
  PetscFunctionReturn(0);
}
