/* Factorization of a body's operator and constrained solves with it. */
#include <mbc/private/bodyimpl.h>
#include <mbc/private/element.h>

/* After a failed factorization: MUMPS's INFOG(1) and ICNTL(14) (both 0 for another package), the
   same on every rank of the body. */
static PetscErrorCode BodyMumpsWorkspace(PC pc, PetscInt *infog1, PetscInt *icntl14)
{
  Mat           F;
  MatSolverType type;
  PetscBool     mumps;

  PetscFunctionBegin;
  *infog1 = *icntl14 = 0;
  PetscCall(PCFactorGetMatrix(pc, &F));
  PetscCall(MatFactorGetSolverType(F, &type));
  PetscCall(PetscStrcmp(type, MATSOLVERMUMPS, &mumps));
  if (!mumps) PetscFunctionReturn(0);
  PetscCall(MatMumpsGetInfog(F, 1, infog1));
  PetscCall(MatMumpsGetIcntl(F, 14, icntl14));
  PetscFunctionReturn(0);
}

/* Whether a MUMPS Cholesky factor of A fits in core, decided before it is computed: the machine's
   memory, not MUMPS, is what runs out first (Linux overcommits, so a factor beyond it is killed,
   not refused). A cheap bound first (8 bytes x 40 N^(4/3): the dams' factors hold 15.6-20
   N^(4/3) entries, docs/performance.md); only a body beyond 3/4 of what this rank has left of
   -mbc_memory_mb gets MUMPS's analysis ahead of the PC's (INFO(15), INFO(17): its estimates in and
   out of core on this rank). Out of core (ICNTL(22) = 1) where in core does not fit; an error that
   names the numbers where out of core does not either. The user's own -mat_mumps_icntl_22 wins.
   Collective on the body. */
static PetscErrorCode BodyFactorPlace(MBCBody body, Mat A, PC pc, const char prefix[])
{
  PetscBool      set;
  PetscLogDouble rss;
  PetscReal      left, bound, est[2] = {0, 0};
  PetscInt       n, info[2];
  PetscMPIInt    bsize, brank;
  int            over[2];
  MatSolverType  type;
  Mat            F;
  MatFactorInfo  finfo;

  PetscFunctionBegin;
  if (body->memory_mb <= 0) PetscFunctionReturn(0);
  PetscCall(PCFactorGetMatSolverType(pc, &type));
  PetscCall(PetscStrcmp(type, MATSOLVERMUMPS, &set));
  if (!set) PetscFunctionReturn(0); /* the user's -pc_factor_mat_solver_type */
  PetscCall(PetscOptionsHasName(NULL, prefix, "-mat_mumps_icntl_22", &set));
  if (set) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_size(body->comm, &bsize));
  PetscCallMPI(MPI_Comm_rank(body->comm, &brank));
  PetscCall(PetscMemoryGetCurrentUsage(&rss));
  left  = body->memory_mb - rss / 1048576.0;
  PetscCall(MatGetSize(A, &n, NULL));
  bound = 8.0 * 40.0 * PetscPowReal((PetscReal)n, 4.0 / 3.0) / bsize / 1048576.0;
  over[0] = bound > 0.75 * left;
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, over, 1, MPI_INT, MPI_MAX, body->comm));
  if (!over[0]) PetscFunctionReturn(0);
  PetscCall(PCFactorSetUpMatSolverType(pc));
  PetscCall(PCFactorGetMatrix(pc, &F));
  PetscCall(MatFactorInfoInitialize(&finfo));
  PetscCall(MatCholeskyFactorSymbolic(F, A, NULL, &finfo)); /* the PC analyses again: the same ordering */
  PetscCall(MatMumpsGetInfo(F, 15, &info[0]));
  PetscCall(MatMumpsGetInfo(F, 17, &info[1]));
  est[0]  = (PetscReal)info[0];
  est[1]  = (PetscReal)info[1];
  over[0] = est[0] > 0.75 * left;
  over[1] = est[1] > left;
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, over, 2, MPI_INT, MPI_MAX, body->comm));
  PetscCheck(!over[1], body->comm, PETSC_ERR_MEM, "Body '%s': MUMPS estimates its factor (%" PetscInt_FMT " DOFs) at %.0f MB on a rank even out of core, and this rank has %.0f MB left of -mbc_memory_mb %.0f (default: its share of the node's available memory): more ranks or nodes, a coarser mesh, or a larger -mbc_memory_mb if the machine has it", body->name, n, (double)est[1], (double)left, (double)body->memory_mb);
  if (over[0]) PetscCall(MatMumpsSetIcntl(F, 22, 1));
  if (!brank) PetscCall(PetscInfo(NULL, "Body %s: MUMPS estimates its factor at %.0f MB in core, %.0f MB out of core on a rank with %.0f MB left of -mbc_memory_mb %.0f: %s\n", body->name, (double)est[0], (double)est[1], (double)left, (double)body->memory_mb, over[0] ? "out of core (ICNTL(22) = 1)" : "in core"));
  PetscFunctionReturn(0);
}

/* A = aK K + aM M with the constrained rows and columns zeroed and 1 on the diagonal
   (MatZeroRowsColumns: eliminating DOFs or a big diagonal number would make the contact
   flexibility matrix singular or ill-conditioned), factored once by a KSP with the options
   body's prefix, [<solver prefix>]body_<name>_ (MBCSolverSetUp copies the -body_ options of all
   bodies to it). The mass matrix alone (aK = 0) is solved by CG with that prefix and mass_. */
PetscErrorCode MBCBodyFactor(MBCBody body, PetscReal aK, PetscReal aM, KSP *newksp, Mat *newA, const char purpose[])
{
  Mat            A;
  KSP            ksp;
  PC             pc;
  char           prefix[256];
  const char    *bodyprefix;
  PCFailedReason reason;

  PetscFunctionBegin;
  if (body->desc.rigid) { /* its six DOFs' projected solve */
    PetscCall(MBCBodyRigidFactor(body, aK, aM, newksp, newA));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscLogEventBegin(MBC_BodyFactor, 0, 0, 0, 0));
  PetscCall(PetscObjectGetOptionsPrefix((PetscObject)body, &bodyprefix));
  if (aK != 0) {
    PetscCall(MatDuplicate(body->K, MAT_COPY_VALUES, &A));
    if (aK != 1) PetscCall(MatScale(A, aK));
    if (aM != 0) PetscCall(MatAXPY(A, aM, body->M, SUBSET_NONZERO_PATTERN));
  } else {
    PetscCall(MatDuplicate(body->M, MAT_COPY_VALUES, &A));
    if (aM != 1) PetscCall(MatScale(A, aM));
  }
  if (aK != 0 && aM != 0 && body->aC != 0 && body->Cb) PetscCall(MatAXPY(A, body->aC, body->Cb, SUBSET_NONZERO_PATTERN)); /* Newmark's a1 Cb: the dashpots */
  if (aK != 0 && body->stab > 0) { /* static stabilisation: a spring stab K_ii on every DOF */
    Vec d;
    PetscCall(MatCreateVecs(A, &d, NULL));
    PetscCall(MatGetDiagonal(body->K, d));
    PetscCall(VecScale(d, aK * body->stab));
    PetscCall(MatDiagonalSet(A, d, ADD_VALUES));
    PetscCall(VecDestroy(&d));
  }
  PetscCall(MatZeroRowsColumns(A, body->nbc, body->bc_rows, 1.0, NULL, NULL));
  if (aK != 0 && aM == 0 && body->nrigid) PetscCall(MatZeroRowsColumns(A, body->nfix, body->fix_rows, 1.0, NULL, NULL)); /* K^+ */
  PetscCall(MatSetOption(A, MAT_SPD, PETSC_TRUE));

  for (PetscInt attempt = 0;; attempt++) {
    PetscInt infog1 = 0, icntl14 = 0;
    PetscCall(KSPCreate(body->comm, &ksp));
    PetscCall(KSPSetOperators(ksp, A, A));
    PetscCall(KSPGetPC(ksp, &pc));
    if (aK != 0) {
      PetscCall(KSPSetType(ksp, KSPPREONLY));
      PetscCall(PCSetType(pc, PCCHOLESKY));
      /* MUMPS: fill-reducing ordering, serial or parallel, and Schur complements for contact later */
      PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
      PetscCall(PetscSNPrintf(prefix, sizeof(prefix), "%s", bodyprefix));
    } else {
      /* the mass matrix alone (initial acceleration): well conditioned, CG needs no factorization */
      PetscCall(KSPSetType(ksp, KSPCG));
      PetscCall(PCSetType(pc, PCJACOBI));
      PetscCall(KSPSetTolerances(ksp, 1e-14, 0.0, PETSC_DEFAULT, 1000));
      PetscCall(PetscSNPrintf(prefix, sizeof(prefix), "%smass_", bodyprefix));
    }
    PetscCall(KSPSetOptionsPrefix(ksp, prefix));
    PetscCall(KSPSetFromOptions(ksp));
    if (aK != 0) PetscCall(BodyFactorPlace(body, A, pc, prefix));
    PetscCall(KSPSetUp(ksp));
    PetscCall(PCGetFailedReasonRank(pc, &reason));
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &reason, 1, MPI_INT, MPI_MAX, body->comm));
    if (reason == PC_NOERROR) break;
    PetscCall(BodyMumpsWorkspace(pc, &infog1, &icntl14));
    /* MUMPS's workspace estimate fell short (INFOG(1) -8, -9: parallel scheduling, oversubscribed
       ranks): factor anew with more (ICNTL(14), as MUMPS's manual advises); a failed factor cannot
       be refactored in place. -13 is the machine's memory: no retry helps. */
    if (reason == PC_FACTOR_OUTMEMORY && infog1 && infog1 != -13 && attempt < 3) {
      char name[300], value[32];
      icntl14 = 2 * PetscMax(icntl14, 20);
      PetscCall(PetscInfo(NULL, "Body %s: MUMPS's workspace ran short (INFOG(1) = %" PetscInt_FMT "): factoring again with ICNTL(14) = %" PetscInt_FMT "\n", body->name, infog1, icntl14));
      PetscCall(PetscSNPrintf(name, sizeof(name), "-%smat_mumps_icntl_14", prefix));
      PetscCall(PetscSNPrintf(value, sizeof(value), "%" PetscInt_FMT, icntl14));
      PetscCall(PetscOptionsSetValue(NULL, name, value)); /* kept: this body's later factorizations start there */
      PetscCall(KSPDestroy(&ksp));
      continue;
    }
    PetscCheck(reason != PC_FACTOR_OUTMEMORY, body->comm, PETSC_ERR_MEM, "Body '%s': factorization of the %s operator ran out of memory (MUMPS INFOG(1) = %" PetscInt_FMT "%s)", body->name, purpose, infog1, infog1 == -13 ? ": the machine's memory; fewer DOFs per rank or more ranks" : ", even with four times the estimated workspace");
    PetscCheck(reason != PC_FACTOR_OTHER || !infog1, body->comm, PETSC_ERR_LIB, "Body '%s': factorization of the %s operator failed (MUMPS INFOG(1) = %" PetscInt_FMT ": MUMPS's manual, error diagnostics)", body->name, purpose, infog1);
    SETERRQ(body->comm, PETSC_ERR_NOT_CONVERGED, "Body '%s': factorization of the %s operator failed (%s); is the body held against rigid-body motion? (static: see -mbc_static_stabilize)", body->name, purpose, PCFailedReasons[reason]);
  }
  PetscCall(PetscLogEventEnd(MBC_BodyFactor, 0, 0, 0, 0));
  *newksp = ksp;
  *newA   = A;
  PetscFunctionReturn(0);
}

/* Solves A x = rhs where A = aK K + aM M was factored with constrained rows/cols zeroed.
   g (or NULL for zero) holds the prescribed values on constrained rows: their columns are
   moved to the right side, as MatZeroRowsColumns would. rhs is overwritten. */
/* rhs = g (or 0 where g is NULL) on the constrained rows. */
PetscErrorCode MBCBodySetConstrainedRows(MBCBody body, Vec g, Vec rhs)
{
  PetscScalar       *r;
  const PetscScalar *gv = NULL;
  PetscInt           rstart;

  PetscFunctionBegin;
  PetscCall(VecGetOwnershipRange(rhs, &rstart, NULL));
  PetscCall(VecGetArray(rhs, &r));
  if (g) PetscCall(VecGetArrayRead(g, &gv));
  for (PetscInt i = 0; i < body->nbc; i++) r[body->bc_rows[i] - rstart] = gv ? gv[body->bc_rows[i] - rstart] : 0.0;
  if (g) PetscCall(VecRestoreArrayRead(g, &gv));
  PetscCall(VecRestoreArray(rhs, &r));
  PetscFunctionReturn(0);
}

/* Checks a solve of the body's factor, on the body's ranks. */
static PetscErrorCode BodySolveCheck(MBCBody body, KSP ksp)
{
  KSPConvergedReason reason;

  PetscFunctionBegin;
  PetscCall(KSPGetConvergedReason(ksp, &reason));
  PetscCheck(reason > 0, body->comm, PETSC_ERR_NOT_CONVERGED, "Body '%s': linear solve failed (%s)", body->name, KSPConvergedReasons[reason]);
  PetscFunctionReturn(0);
}

/* Solves A x = rhs where A = aK K + aM M was factored with constrained rows/cols zeroed.
   g (or NULL for zero) holds the prescribed values on constrained rows: their columns are
   moved to the right side, as MatZeroRowsColumns would. rhs is overwritten. */
PetscErrorCode MBCBodyConstrainedSolve(MBCBody body, KSP ksp, PetscReal aK, PetscReal aM, Vec g, Vec rhs, Vec x)
{
  PetscFunctionBegin;
  if (body->desc.rigid) {
    PetscCall(MBCBodyRigidSolve(body, ksp, aM, g, rhs, x));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscLogEventBegin(MBC_BodySolve, 0, 0, 0, 0));
  if (g) { /* most steps prescribe nothing new (fixed supports): two products with K and M saved */
    PetscReal gmax;
    PetscCall(VecNorm(g, NORM_INFINITY, &gmax));
    if (gmax == 0) g = NULL;
  }
  if (g) {
    if (aK != 0) {
      PetscCall(MatMult(body->K, g, body->work));
      PetscCall(VecAXPY(rhs, -aK, body->work));
    }
    if (aM != 0) {
      PetscCall(MatMult(body->M, g, body->work));
      PetscCall(VecAXPY(rhs, -aM, body->work));
    }
  }
  PetscCall(MBCBodySetConstrainedRows(body, g, rhs));
  if (aK != 0 && aM == 0 && body->nrigid) { /* x = K^+ rhs: the held rows 0 */
    PetscCall(MBCBodyZeroHeldRows(body, rhs, NULL));
  }
  PetscCall(KSPSolve(ksp, rhs, x));
  PetscCall(BodySolveCheck(body, ksp));
  PetscCall(PetscLogEventEnd(MBC_BodySolve, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* y = A^+ x: the body's current factor (its stage's, its step size's) on x with x's held rows
   zeroed in a copy. A body solve like the step's own (MBC_BodySolve), so that the log compares
   the contact's work with every solve of the bodies. */
static PetscErrorCode BodyInverseMult(Mat Ainv, Vec x, Vec y)
{
  MBCBody body;

  PetscFunctionBegin;
  PetscCall(MatShellGetContext(Ainv, &body));
  PetscCall(PetscLogEventBegin(MBC_BodySolve, 0, 0, 0, 0));
  if (body->nrigid) { /* nrigid, not this rank's nfix: every rank of the body creates the same objects */
    if (!body->fheld) PetscCall(VecDuplicate(x, &body->fheld));
    PetscCall(VecCopy(x, body->fheld));
    PetscCall(MBCBodyZeroHeldRows(body, body->fheld, NULL));
    x = body->fheld;
  }
  PetscCall(KSPSolve(body->ksp, x, y));
  PetscCall(BodySolveCheck(body, body->ksp));
  PetscCall(PetscLogEventEnd(MBC_BodySolve, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* C = A^+ B for a dense B of several right sides: one multi-right-hand-side solve. Not logged as
   MBC_BodySolve: it builds D or a coarse space (their own events), and bench/quake.py's ratio of
   the interface's work to the bodies' solves would count it on both sides. */
static PetscErrorCode BodyInverseMatMult(Mat Ainv, Mat B, Mat C, void *ctx)
{
  MBCBody body;
  Mat     Bheld = NULL;

  PetscFunctionBegin;
  PetscCall(MatShellGetContext(Ainv, &body));
  if (body->nrigid) {
    PetscCall(MatDuplicate(B, MAT_COPY_VALUES, &Bheld));
    PetscCall(MBCBodyZeroHeldRows(body, NULL, Bheld));
    B = Bheld;
  }
  PetscCall(KSPMatSolve(body->ksp, B, C));
  PetscCall(MatDestroy(&Bheld));
  PetscFunctionReturn(0);
}

/* The body's generalised inverse as an operator (as PERMON's MatCreateInv): MatMult and, for a
   dense B, MatMatMult apply A^-1 by the body's current factor with the held rows of the right
   side zeroed, which is K^+ where a static body floats; its free rigid modes are then the Mat's
   null space. The body keeps it (no reference is given): after the body's factor changes (a stage,
   a step size) it applies the new one. Collective on the body the first time. */
PetscErrorCode MBCBodyGetInverse(MBCBody body, Mat *Ainv)
{
  MatNullSpace nsp;

  PetscFunctionBegin;
  if (!body->Ainv) {
    PetscInt n, N;
    PetscCall(VecGetLocalSize(body->u, &n));
    PetscCall(VecGetSize(body->u, &N));
    PetscCall(MatCreateShell(body->comm, n, n, N, N, body, &body->Ainv));
    PetscCall(MatShellSetOperation(body->Ainv, MATOP_MULT, (void (*)(void))BodyInverseMult));
    PetscCall(MatShellSetMatProductOperation(body->Ainv, MATPRODUCT_AB, NULL, BodyInverseMatMult, NULL, MATDENSE, MATDENSE));
  }
  PetscCall(MatGetNullSpace(body->Ainv, &nsp));
  if (body->nrigid && !nsp) { /* the modes of this static stage (MBCBodyRigidModesDestroy drops it) */
    PetscCall(MatNullSpaceCreate(body->comm, PETSC_FALSE, body->nrigid, body->rigid, &nsp));
    PetscCall(MatSetNullSpace(body->Ainv, nsp));
    PetscCall(MatNullSpaceDestroy(&nsp));
  }
  *Ainv = body->Ainv;
  PetscFunctionReturn(0);
}

/* The KSP of the factor that MBCBodyGetInverse's Mat applies now (PERMON's MatInvGetKSP). */
PetscErrorCode MBCInverseGetKSP(Mat Ainv, KSP *ksp)
{
  MBCBody body;

  PetscFunctionBegin;
  PetscCall(MatShellGetContext(Ainv, &body));
  *ksp = body->ksp;
  PetscFunctionReturn(0);
}

/* F = sum of the body's loads times their time factors at t; constantOnly keeps the loads
   that are present from the start. */
PetscErrorCode MBCBodyExternalForce(MBCBody body, PetscReal t, PetscBool constantOnly, Vec F)
{
  PetscFunctionBegin;
  PetscCall(VecZeroEntries(F));
  for (PetscInt i = 0; i < body->nloads; i++) {
    MBCLoadDesc *load = &body->scene->loads[body->load_index[i]];
    PetscReal    factor;

    if (constantOnly && load->time != MBC_TIME_CONSTANT) continue;
    if (load->stage > body->stage) continue;
    if (load->kind == MBC_LOAD_GROUND_ACCELERATION && body->scene->absolute) { /* through the input surfaces, with the record's velocity */
      PetscReal d, a;
      PetscCall(MBCSceneRecord(body->scene, load, t, &d, &factor, &a));
    } else PetscCall(MBCTimeFactor(body->scene, load->time, load->time_function, t, &factor));
    if (factor != 0) PetscCall(VecAXPY(F, factor, body->load[i]));
  }
  if (body->fhold && !body->held) PetscCall(VecAXPY(F, 1.0, body->fhold)); /* what the released absorbing surfaces carried */
  PetscFunctionReturn(0);
}

/* g = prescribed displacement at time t on the constrained rows, 0 elsewhere. */
PetscErrorCode MBCBodyPrescribed(MBCBody body, PetscReal t, Vec g)
{
  PetscScalar *gv;
  PetscInt     rstart;

  PetscFunctionBegin;
  if (body->desc.rigid) {
    PetscCall(MBCBodyRigidPrescribed(body, t, NULL, g));
    PetscFunctionReturn(0);
  }
  PetscCall(VecZeroEntries(g));
  PetscCall(VecGetOwnershipRange(g, &rstart, NULL));
  PetscCall(VecGetArray(g, &gv));
  for (PetscInt i = 0; i < body->nbc; i++) {
    MBCDirichletDesc *d = body->bc_entry[i] >= 0 ? &body->scene->dirichlet[body->bc_entry[i]] : NULL; /* < 0: a held absorbing surface */
    PetscReal         factor = 0;

    if (d) PetscCall(MBCTimeFactor(body->scene, d->time, d->time_function, t, &factor));
    gv[body->bc_rows[i] - rstart] = d ? d->value * factor : 0.0;
  }
  PetscCall(VecRestoreArray(g, &gv));
  PetscFunctionReturn(0);
}

/* g = prescribed displacement at time t minus the current one on the constrained rows, 0
   elsewhere: the increments an incremental step imposes. */
PetscErrorCode MBCBodyPrescribedIncrement(MBCBody body, PetscReal t, Vec g)
{
  PetscScalar       *gv;
  const PetscScalar *uv;
  PetscInt           rstart;

  PetscFunctionBegin;
  if (body->desc.rigid) {
    PetscCall(MBCBodyRigidPrescribed(body, t, body->u, g));
    PetscFunctionReturn(0);
  }
  PetscCall(MBCBodyPrescribed(body, t, g));
  PetscCall(VecGetOwnershipRange(g, &rstart, NULL));
  PetscCall(VecGetArray(g, &gv));
  PetscCall(VecGetArrayRead(body->u, &uv));
  for (PetscInt i = 0; i < body->nbc; i++) gv[body->bc_rows[i] - rstart] -= uv[body->bc_rows[i] - rstart];
  PetscCall(VecRestoreArrayRead(body->u, &uv));
  PetscCall(VecRestoreArray(g, &gv));
  PetscFunctionReturn(0);
}

/* The cell stress (P0, Voigt order xx yy zz xy yz xz) from grad u at the cell's reference centre,
   by hand as K is (PetscFE's projection took 1.2 s of the 198k dam's output). hex8b: its volumetric
   strain is the cell mean of div u, not its centre value, so the normal stresses get
   kappa (mean - centre) (kappa = lambda + 2 mu / 3): the written stress is the B-bar element's
   own, deviatoric part at the centre plus the cell's mean pressure. The two dilatations agree on a
   parallelepiped (the centre value of a trilinear field's gradient is then its 2x2x2 mean) and
   differ on any other cell, where near nu = 1/2 the centre value of kappa div u is pressure noise
   of the order of the stress itself. */
PetscErrorCode MBCBodyComputeStress(MBCBody body, Vec u, Vec stress)
{
  Vec                coords, ul;
  const PetscScalar *x, *uv;
  PetscScalar       *sv;
  PetscInt           cStart, cEnd;
  const PetscReal    lambda = body->lambda, mu = body->mu, kappa = lambda + 2.0 * mu / 3.0;

  PetscFunctionBegin;
  if (body->desc.rigid) { /* no strain */
    PetscCall(VecZeroEntries(stress));
    PetscFunctionReturn(0);
  }
  PetscCall(DMGetCoordinatesLocal(body->dm, &coords));
  PetscCall(DMGetLocalVector(body->dm, &ul));
  PetscCall(DMGlobalToLocal(body->dm, u, INSERT_VALUES, ul));
  PetscCall(VecGetArrayRead(coords, &x));
  PetscCall(VecGetArrayRead(ul, &uv));
  PetscCall(VecGetArray(stress, &sv));
  PetscCall(DMPlexGetHeightStratum(body->dm, 0, &cStart, &cEnd));
  for (PetscInt c = cStart; c < cEnd; c++) {
    PetscInt     idx[3 * MBC_MAX_CELL_NODES], nv;
    PetscReal    X[3 * MBC_MAX_CELL_NODES], U[3 * MBC_MAX_CELL_NODES], g[9], tr;
    PetscScalar *s;

    PetscCall(DMPlexPointGlobalRef(body->dmStress, c, sv, &s));
    if (!s) continue; /* not owned */
    PetscCall(MBCBodyCellVertices(body, c, x, X, idx, &nv));
    for (PetscInt i = 0; i < 3 * nv; i++) U[i] = PetscRealPart(uv[idx[i]]);
    MBCElementCentreGradient(nv, X, U, g);
    tr   = g[0] + g[4] + g[8];
    s[0] = lambda * tr + 2 * mu * g[0];
    s[1] = lambda * tr + 2 * mu * g[4];
    s[2] = lambda * tr + 2 * mu * g[8];
    s[3] = mu * (g[1] + g[3]);
    s[4] = mu * (g[5] + g[7]);
    s[5] = mu * (g[2] + g[6]);
    if (body->element == MBC_ELEMENT_HEX8B && nv == 8) {
      PetscReal centre, mean;
      MBCElementHex8Dilatation(X, U, &centre, &mean);
      for (PetscInt i = 0; i < 3; i++) s[i] += kappa * (mean - centre);
    }
  }
  PetscCall(VecRestoreArray(stress, &sv));
  PetscCall(VecRestoreArrayRead(ul, &uv));
  PetscCall(VecRestoreArrayRead(coords, &x));
  PetscCall(DMRestoreLocalVector(body->dm, &ul));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyCheckFinite(MBCBody body, Vec x, const char what[], PetscReal t)
{
  PetscReal norm;

  PetscFunctionBegin;
  PetscCall(VecNorm(x, NORM_INFINITY, &norm));
  PetscCheck(!PetscIsInfOrNanReal(norm), body->comm, PETSC_ERR_FP, "Body '%s': the %s is not finite at time %g (check the scene's numbers and the body's constraints)", body->name, what, (double)t);
  PetscFunctionReturn(0);
}

/* r = K u (+ M a + cM M v + cK K v, dynamic) on the prescribed rows (bc_rows), 0 elsewhere: the
   internal, inertial and damping forces the supports carry (the reactions). Through K's and M's
   rows bc_rows alone, taken once per set of prescribed rows: the whole products cost four passes
   over the body's matrices at every written step, for a few hundred rows. The same sums in the
   same order as the whole rows'. */
PetscErrorCode MBCBodyPrescribedRowsForce(MBCBody body, PetscBool dynamic, Vec r)
{
  Vec                rs, w;
  const PetscScalar *rv;
  PetscScalar       *fv;
  PetscInt           r0;

  PetscFunctionBegin;
  if (body->Kbc) {
    PetscInt m;
    PetscCall(MatGetLocalSize(body->Kbc, &m, NULL));
    if (m != body->nbc) body->bcrows_of = NULL;
  }
  if (body->bcrows_of != body->bc_rows) {
    PetscCall(MatDestroy(&body->Kbc));
    PetscCall(MatDestroy(&body->Mbc));
    body->bcrows_of = body->bc_rows;
  }
  if (!body->Kbc || (dynamic && !body->Mbc)) { /* M: dynamic analyses only */
    IS       rows, cols;
    PetscInt c0, c1;
    PetscCall(ISCreateGeneral(body->comm, body->nbc, body->bc_rows, PETSC_USE_POINTER, &rows));
    PetscCall(MatGetOwnershipRangeColumn(body->K, &c0, &c1));
    PetscCall(ISCreateStride(body->comm, c1 - c0, c0, 1, &cols));
    if (!body->Kbc) PetscCall(MatCreateSubMatrix(body->K, rows, cols, MAT_INITIAL_MATRIX, &body->Kbc));
    if (dynamic && !body->Mbc) PetscCall(MatCreateSubMatrix(body->M, rows, cols, MAT_INITIAL_MATRIX, &body->Mbc));
    PetscCall(ISDestroy(&rows));
    PetscCall(ISDestroy(&cols));
  }
  PetscCall(MatCreateVecs(body->Kbc, NULL, &rs));
  PetscCall(MatMult(body->Kbc, body->u, rs));
  if (dynamic) {
    PetscCall(MatMultAdd(body->Mbc, body->a, rs, rs));
    if (body->cM != 0 || body->cK != 0) {
      PetscCall(VecDuplicate(rs, &w));
      PetscCall(MatMult(body->Mbc, body->v, w));
      PetscCall(VecAXPY(rs, body->cM, w));
      PetscCall(MatMult(body->Kbc, body->v, w));
      PetscCall(VecAXPY(rs, body->cK, w));
      PetscCall(VecDestroy(&w));
    }
  }
  PetscCall(VecSet(r, 0.0));
  PetscCall(VecGetOwnershipRange(r, &r0, NULL));
  PetscCall(VecGetArrayRead(rs, &rv));
  PetscCall(VecGetArray(r, &fv));
  for (PetscInt i = 0; i < body->nbc; i++) fv[body->bc_rows[i] - r0] = rv[i];
  PetscCall(VecRestoreArray(r, &fv));
  PetscCall(VecRestoreArrayRead(rs, &rv));
  PetscCall(VecDestroy(&rs));
  PetscFunctionReturn(0);
}
