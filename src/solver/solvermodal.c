/* Modal analysis (analysis type modal, docs/scene.md): the lowest natural frequencies and modes of
   the scene, K phi = omega^2 M phi, by SLEPc's Krylov-Schur with shift-and-invert (MUMPS LU), M
   with the reservoir's added mass, the prescribed DOFs held. With the couples tied (the usual
   assumption of a dam's modal check, -mbc_modal_tie, default the scene's `tie`) every contact
   point of the initial search is bonded in x, y and z: its constraint g = sum mw_j u_j - sum
   sw_j u_j (MBCCoupleIntegrate, the dual-mortar weights the contact uses) = 0 by a Lagrange
   multiplier, the saddle-point pencil

       [K  H; H^T -eps I] x = omega^2 [M 0; 0 0] x,

   eps = 1e-10 / max diag K: a regularisation that keeps the pencil regular where constraints are
   linearly dependent (a master node on a joint and on the base), a spring 1e10 times the stiffest
   diagonal otherwise. The bodies of all ranks are gathered into one matrix on the solver's
   communicator (a body's rows on the ranks that hold them), so the bodies' sub-communicators
   need no eigensolver of their own. Output: each mode as an output step of the result file
   (time = its frequency in Hz; displacement = the mode shape, mass-normalised, and its stress),
   /modes (frequency, period, participation factors, effective masses), a table on stdout. */
#include <mbc/private/solverimpl.h>
#include <mbc/private/h5util.h>
#include <slepceps.h>
#include <math.h>

PetscErrorCode MBCSolverModalSetFromOptions(MBCSolver s)
{
  PetscFunctionBegin;
  s->modal_nev = s->scene->modal_modes;
  s->modal_tie = s->scene->modal_tie;
  PetscObjectOptionsBegin((PetscObject)s);
  PetscCall(PetscOptionsInt("-mbc_modal_nev", "Modal analysis: how many of the lowest modes", "MBCSolverModalSolve", s->modal_nev, &s->modal_nev, NULL));
  PetscCall(PetscOptionsBool("-mbc_modal_tie", "Modal analysis: the contact couples tied (bonded) at the initial contact points, or the bodies alone", "MBCSolverModalSolve", s->modal_tie, &s->modal_tie, NULL));
  PetscOptionsEnd();
  PetscCheck(s->modal_nev >= 1 && s->modal_nev <= 10000, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_modal_nev %" PetscInt_FMT ": must lie in [1, 10000]", s->modal_nev);
  PetscFunctionReturn(0);
}

/* Where every body's rows are in the gathered system: per body b and rank r of the solver, the
   body rows [lo, hi) that rank owns start at world row wstart. */
typedef struct {
  PetscInt *lo, *hi, *wstart; /* nbodies x size */
  PetscInt  size, nlocal, rstart;       /* the world layout: this rank's rows */
  PetscInt  nmult, mfirst, mlocal, mstart; /* multipliers [mfirst, mfirst + mlocal) are this rank's, at local row mstart */
  PetscInt *boff; /* per body: this rank's first local row of its block (-1 off the body) */
} ModalLayout;

static PetscInt WorldRow(const ModalLayout *L, PetscInt b, PetscInt row)
{
  for (PetscInt r = 0; r < L->size; r++) {
    const PetscInt i = b * L->size + r;
    if (row >= L->lo[i] && row < L->hi[i]) return L->wstart[i] + row - L->lo[i];
  }
  return -1;
}

static PetscErrorCode ModalLayoutCreate(MBCSolver s, PetscInt nmult, ModalLayout *L)
{
  PetscMPIInt size, rank;
  PetscInt   *mine;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  L->size   = size;
  L->nmult  = nmult;
  L->mlocal = PETSC_DECIDE;
  PetscCall(PetscSplitOwnership(s->comm, &L->mlocal, &nmult));
  PetscCallMPI(MPI_Scan(&L->mlocal, &L->mfirst, 1, MPIU_INT, MPI_SUM, s->comm));
  L->mfirst -= L->mlocal;
  PetscCall(PetscMalloc4(s->nbodies * size, &L->lo, s->nbodies * size, &L->hi, s->nbodies * size, &L->wstart, s->nbodies, &L->boff));
  PetscCall(PetscCalloc1(3 * s->nbodies, &mine));
  L->nlocal = 0;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    Vec u;
    L->boff[b] = -1;
    if (!s->bodies[b]) continue;
    PetscCall(MBCBodyGetDisplacement(s->bodies[b], &u));
    PetscCall(VecGetOwnershipRange(u, &mine[3 * b], &mine[3 * b + 1]));
    L->boff[b] = L->nlocal;
    L->nlocal += mine[3 * b + 1] - mine[3 * b];
  }
  L->mstart = L->nlocal; /* the multipliers after this rank's bodies */
  L->nlocal += L->mlocal;
  PetscCallMPI(MPI_Scan(&L->nlocal, &L->rstart, 1, MPIU_INT, MPI_SUM, s->comm));
  L->rstart -= L->nlocal;
  for (PetscInt b = 0; b < s->nbodies; b++) mine[3 * b + 2] = L->boff[b] >= 0 ? L->rstart + L->boff[b] : 0;
  {
    PetscInt *all;
    PetscCall(PetscMalloc1(3 * s->nbodies * size, &all));
    PetscCallMPI(MPI_Allgather(mine, 3 * (PetscMPIInt)s->nbodies, MPIU_INT, all, 3 * (PetscMPIInt)s->nbodies, MPIU_INT, s->comm));
    for (PetscInt r = 0; r < size; r++)
      for (PetscInt b = 0; b < s->nbodies; b++) {
        L->lo[b * size + r]     = all[3 * (r * s->nbodies + b)];
        L->hi[b * size + r]     = all[3 * (r * s->nbodies + b) + 1];
        L->wstart[b * size + r] = all[3 * (r * s->nbodies + b) + 2];
      }
    PetscCall(PetscFree(all));
  }
  PetscCall(PetscFree(mine));
  PetscFunctionReturn(0);
}

static PetscErrorCode ModalLayoutDestroy(ModalLayout *L)
{
  PetscFunctionBegin;
  PetscCall(PetscFree4(L->lo, L->hi, L->wstart, L->boff));
  PetscFunctionReturn(0);
}

/* Inserts K (or M) of this rank's bodies, and with K the tie constraints and -eps on the
   multipliers' diagonal, into A (a preallocator or the matrix). The constraints of multiplier m
   (3 per contact point, x y z, couple order) are inserted by the rank that owns row m. */
static PetscErrorCode ModalInsert(MBCSolver s, const ModalLayout *L, PetscBool stiffness, PetscReal eps, PetscBool pattern, Mat A)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody  body = s->bodies[b];
    Mat      X;
    PetscInt rlo, rhi;
    if (!body) continue;
    PetscCall(MBCBodyGetOperators(body, stiffness ? &X : NULL, stiffness ? NULL : &X, NULL));
    PetscCall(MatGetOwnershipRange(X, &rlo, &rhi));
    for (PetscInt row = rlo; row < rhi; row++) {
      const PetscInt    *cols;
      const PetscScalar *vals;
      PetscInt           ncols, wrow = L->rstart + L->boff[b] + row - rlo, *wcols;
      PetscScalar       *wvals;
      PetscCall(MatGetRow(X, row, &ncols, &cols, &vals));
      PetscCall(PetscMalloc2(ncols, &wcols, ncols, &wvals));
      for (PetscInt j = 0; j < ncols; j++) {
        wcols[j] = WorldRow(L, b, cols[j]);
        wvals[j] = pattern ? 1.0 : vals[j];
      }
      PetscCall(MatSetValues(A, 1, &wrow, ncols, wcols, wvals, INSERT_VALUES));
      PetscCall(PetscFree2(wcols, wvals));
      PetscCall(MatRestoreRow(X, row, &ncols, &cols, &vals));
    }
  }
  if (stiffness && L->nmult) { /* the ties: every rank holds the contact points */
    MBCContact c = s->contact;
    PetscInt   m = 0;
    for (PetscInt i = 0; i < c->ncouples; i++) {
      MBCCouple *cp = &c->couples[i];
      for (PetscInt k = 0; k < cp->npoints; k++, m += 3) {
        for (PetscInt d = 0; d < 3; d++) {
          const PetscInt mrow = m + d; /* multiplier index */
          PetscInt       wm;
          if (mrow < L->mfirst || mrow >= L->mfirst + L->mlocal) continue;
          wm = L->rstart + L->mstart + mrow - L->mfirst;
          {
            const PetscScalar diag = pattern ? 1.0 : -eps;
            PetscCall(MatSetValues(A, 1, &wm, 1, &wm, &diag, INSERT_VALUES));
          }
          for (PetscInt side = 0; side < 2; side++) {
            const MBCSurface *sf  = side ? &cp->slave : &cp->master;
            const PetscInt    lo  = side ? cp->soff[k] : cp->moff[k], hi = side ? cp->soff[k + 1] : cp->moff[k + 1];
            const PetscInt   *nod = side ? cp->snode : cp->mnode;
            const PetscReal  *w   = side ? cp->sw : cp->mw;
            for (PetscInt l = lo; l < hi; l++) {
              const PetscInt node = nod[l], wr = WorldRow(L, sf->nbody[node], sf->nrow[node] + d);
              PetscScalar    v    = pattern ? 1.0 : (side ? -w[l] : w[l]);
              PetscCheck(wr >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Modal analysis: a contact node's row is in no rank's block");
              PetscCall(MatSetValues(A, 1, &wm, 1, &wr, &v, INSERT_VALUES)); /* a node once per side: no sums */
              PetscCall(MatSetValues(A, 1, &wr, 1, &wm, &v, INSERT_VALUES));
            }
          }
        }
      }
    }
  }
  PetscFunctionReturn(0);
}

/* The gathered pencil (Ksys, Bsys) with the prescribed rows held (1 on K's diagonal, 0 on M's:
   their modes are at infinity). */
static PetscErrorCode ModalOperators(MBCSolver s, const ModalLayout *L, Mat *Ksys, Mat *Bsys, PetscReal *eps)
{
  Mat       pre;
  PetscInt  N, nbc = 0, *rows, k = 0;
  PetscReal kmax = 0;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    Vec       d;
    Mat       K;
    PetscReal m;
    PetscInt  nbcb;
    if (!s->bodies[b]) continue;
    PetscCall(MBCBodyGetOperators(s->bodies[b], &K, NULL, NULL));
    PetscCall(MatCreateVecs(K, &d, NULL));
    PetscCall(MatGetDiagonal(K, d));
    PetscCall(VecNorm(d, NORM_INFINITY, &m));
    PetscCall(VecDestroy(&d));
    kmax = PetscMax(kmax, m);
    PetscCall(MBCBodyGetPrescribedRows(s->bodies[b], &nbcb, NULL));
    nbc += nbcb;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &kmax, 1, MPIU_REAL, MPIU_MAX, s->comm));
  *eps = 1e-10 / kmax;
  PetscCall(MatCreate(s->comm, &pre));
  PetscCall(MatSetSizes(pre, L->nlocal, L->nlocal, PETSC_DETERMINE, PETSC_DETERMINE));
  PetscCall(MatSetType(pre, MATPREALLOCATOR));
  PetscCall(MatSetUp(pre));
  PetscCall(ModalInsert(s, L, PETSC_TRUE, *eps, PETSC_TRUE, pre));
  PetscCall(MatAssemblyBegin(pre, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(pre, MAT_FINAL_ASSEMBLY));
  PetscCall(MatGetSize(pre, &N, NULL));
  PetscCall(MatCreateAIJ(s->comm, L->nlocal, L->nlocal, N, N, 0, NULL, 0, NULL, Ksys));
  PetscCall(MatPreallocatorPreallocate(pre, PETSC_TRUE, *Ksys));
  PetscCall(MatDestroy(&pre));
  PetscCall(MatDuplicate(*Ksys, MAT_DO_NOT_COPY_VALUES, Bsys));
  PetscCall(ModalInsert(s, L, PETSC_TRUE, *eps, PETSC_FALSE, *Ksys));
  PetscCall(ModalInsert(s, L, PETSC_FALSE, 0, PETSC_FALSE, *Bsys));
  PetscCall(MatAssemblyBegin(*Ksys, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*Ksys, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyBegin(*Bsys, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*Bsys, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscMalloc1(nbc, &rows));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody         body = s->bodies[b];
    Vec             u;
    PetscInt        rlo, nbcb;
    const PetscInt *bcrows;
    if (!body) continue;
    PetscCall(MBCBodyGetDisplacement(body, &u));
    PetscCall(MBCBodyGetPrescribedRows(body, &nbcb, &bcrows));
    PetscCall(VecGetOwnershipRange(u, &rlo, NULL));
    for (PetscInt i = 0; i < nbcb; i++) rows[k++] = L->rstart + L->boff[b] + bcrows[i] - rlo;
  }
  PetscCall(MatZeroRowsColumns(*Ksys, nbc, rows, 1.0, NULL, NULL));
  PetscCall(MatZeroRowsColumns(*Bsys, nbc, rows, 0.0, NULL, NULL));
  PetscCall(PetscFree(rows));
  PetscCall(MatSetOption(*Ksys, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(MatSetOption(*Bsys, MAT_SYMMETRIC, PETSC_TRUE));
  PetscFunctionReturn(0);
}

/* The world vector's body block of body b into its displacement (this rank's rows). */
static PetscErrorCode ModalToBodies(MBCSolver s, const ModalLayout *L, Vec x)
{
  const PetscScalar *xa;

  PetscFunctionBegin;
  PetscCall(VecGetArrayRead(x, &xa));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscScalar *u;
    PetscInt     n;
    Vec          ub;
    if (!s->bodies[b]) continue;
    PetscCall(MBCBodyGetDisplacement(s->bodies[b], &ub));
    PetscCall(VecGetLocalSize(ub, &n));
    PetscCall(VecGetArray(ub, &u));
    PetscCall(PetscArraycpy(u, xa + L->boff[b], n));
    PetscCall(VecRestoreArray(ub, &u));
  }
  PetscCall(VecRestoreArrayRead(x, &xa));
  PetscFunctionReturn(0);
}

/* iota_d: 1 on the d components of the bodies' rows, 0 on the multipliers. */
static PetscErrorCode ModalDirection(MBCSolver s, const ModalLayout *L, PetscInt d, Vec e)
{
  PetscScalar *ea;

  PetscFunctionBegin;
  PetscCall(VecZeroEntries(e));
  PetscCall(VecGetArray(e, &ea));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscInt n, rlo;
    Vec      u;
    if (!s->bodies[b]) continue;
    PetscCall(MBCBodyGetDisplacement(s->bodies[b], &u));
    PetscCall(VecGetLocalSize(u, &n));
    PetscCall(VecGetOwnershipRange(u, &rlo, NULL));
    for (PetscInt i = 0; i < n; i++) ea[L->boff[b] + i] = ((rlo + i) % 3 == d) ? 1.0 : 0.0;
  }
  PetscCall(VecRestoreArray(e, &ea));
  PetscFunctionReturn(0);
}

/* Writes /modes to the result file (rank 0's rows, collective). */
static PetscErrorCode ModalWrite(MBCSolver s, PetscInt n, const PetscReal freq[], const PetscReal gamma[], const PetscReal meff[], const PetscReal mtot[3])
{
  PetscMPIInt rank;
  hid_t       g;
  PetscReal  *period;
  int         count = (int)n;

  PetscFunctionBegin;
  if (s->h5 < 0) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscMalloc1(n, &period));
  for (PetscInt i = 0; i < n; i++) period[i] = freq[i] > 0 ? 1.0 / freq[i] : (PetscReal)INFINITY; /* a rigid mode */
  PetscCall(MBCH5GroupCreate((hid_t)s->h5, "modes", PETSC_FALSE, &g));
  PetscCall(MBCH5WriteAttribute(g, "count", H5T_NATIVE_INT, 1, &count));
  PetscCall(MBCH5WriteAttribute(g, "total_mass", H5T_NATIVE_DOUBLE, 3, mtot));
  PetscCall(MBCH5WriteRows(g, "frequency", H5T_NATIVE_DOUBLE, n, 1, 0, rank ? 0 : n, freq));
  PetscCall(MBCH5WriteRows(g, "period", H5T_NATIVE_DOUBLE, n, 1, 0, rank ? 0 : n, period));
  PetscCall(MBCH5WriteRows(g, "participation", H5T_NATIVE_DOUBLE, n, 3, 0, rank ? 0 : n, gamma));
  PetscCall(MBCH5WriteRows(g, "effective_mass", H5T_NATIVE_DOUBLE, n, 3, 0, rank ? 0 : n, meff));
  PetscCall(MBCH5GroupClose(&g));
  PetscCall(PetscFree(period));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverModalSolve(MBCSolver s)
{
  ModalLayout L;
  Mat         K, B;
  EPS         eps;
  ST          st;
  KSP         ksp;
  PC          pc;
  Vec         x, Bx, e[3];
  PetscInt    nmult = 0, nconv, n;
  PetscReal   reg, sigma, mtot[3], *freq, *gamma, *meff, kdiag = 0, mdiag = 0;
  MBCContact  contact = s->contact;
  char        prefix[256];

  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->scene->nbodies; b++) PetscCheck(!s->scene->bodies[b].rigid, s->comm, PETSC_ERR_SUP, "Scene file %s: body '%s' is rigid: the modal analysis takes deformable bodies only (model it as an elastic body, or leave it out)", s->scene->filename, s->scene->bodies[b].name);
  /* SLEPc on the PETSc already running (mbcontact's or petsc4py's); its classes are finalised with PETSc */
  PetscCall(SlepcInitialize(NULL, NULL, NULL, NULL));
  if (contact && s->modal_tie)
    for (PetscInt i = 0; i < contact->ncouples; i++) nmult += 3 * contact->couples[i].npoints;
  PetscCall(ModalLayoutCreate(s, nmult, &L));
  PetscCall(ModalOperators(s, &L, &K, &B, &reg));
  /* the shift: below the lowest eigenvalue (all are >= 0), so the nearest to it are the lowest;
     1e-6 of the largest stiffness-to-mass ratio of a diagonal entry, at most */
  {
    Vec dk, dm;
    PetscCall(MatCreateVecs(K, &dk, &dm));
    PetscCall(MatGetDiagonal(K, dk));
    PetscCall(MatGetDiagonal(B, dm));
    PetscCall(VecSum(dk, &kdiag));
    PetscCall(VecSum(dm, &mdiag));
    PetscCall(VecDestroy(&dk));
    PetscCall(VecDestroy(&dm));
  }
  PetscCheck(mdiag > 0, s->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: a modal analysis needs mass: every body is massless or held", s->scene->filename);
  sigma = -1e-6 * PetscRealPart(kdiag) / PetscRealPart(mdiag);

  PetscCall(EPSCreate(s->comm, &eps));
  PetscCall(EPSSetOperators(eps, K, B));
  PetscCall(EPSSetProblemType(eps, EPS_GHEP)); /* B semi-definite (the multipliers, the held rows): purified */
  /* a wide subspace: the bodies alone have up to six rigid modes each at 0 Hz, a repeated
     eigenvalue a narrow Krylov space misses (SLEPc's default ncv 21 found 5 of a floating block's 6) */
  PetscCall(EPSSetDimensions(eps, s->modal_nev, s->modal_nev + PetscMax(s->modal_nev, 30), PETSC_DEFAULT));
  PetscCall(EPSSetWhichEigenpairs(eps, EPS_TARGET_MAGNITUDE));
  PetscCall(EPSSetTarget(eps, sigma));
  PetscCall(EPSSetTolerances(eps, 1e-10, PETSC_DEFAULT));
  PetscCall(EPSGetST(eps, &st));
  PetscCall(STSetType(st, STSINVERT));
  PetscCall(STGetKSP(st, &ksp));
  PetscCall(KSPSetType(ksp, KSPPREONLY));
  PetscCall(KSPGetPC(ksp, &pc));
  PetscCall(PCSetType(pc, PCLU)); /* indefinite with the multipliers */
  PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERMUMPS));
  PetscCall(PetscSNPrintf(prefix, sizeof(prefix), "%smbc_modal_", ((PetscObject)s)->prefix ? ((PetscObject)s)->prefix : ""));
  PetscCall(EPSSetOptionsPrefix(eps, prefix));
  PetscCall(EPSSetFromOptions(eps));
  PetscCall(EPSSolve(eps));
  PetscCall(EPSGetConverged(eps, &nconv));
  PetscCheck(nconv >= s->modal_nev, s->comm, PETSC_ERR_NOT_CONVERGED, "Scene file %s: the modal analysis found %" PetscInt_FMT " of the %" PetscInt_FMT " modes asked (-mbc_modal_nev); -mbc_modal_eps_max_it or -mbc_modal_eps_ncv may help", s->scene->filename, nconv, s->modal_nev);
  n = s->modal_nev;

  PetscCall(MatCreateVecs(K, &x, &Bx));
  for (PetscInt d = 0; d < 3; d++) {
    PetscScalar m;
    PetscCall(VecDuplicate(x, &e[d]));
    PetscCall(ModalDirection(s, &L, d, e[d]));
    PetscCall(MatMult(B, e[d], Bx));
    PetscCall(VecDot(e[d], Bx, &m));
    mtot[d] = PetscRealPart(m);
  }
  PetscCall(PetscMalloc3(n, &freq, 3 * n, &gamma, 3 * n, &meff));
  PetscCall(PetscFree(s->modal_freq));
  PetscCall(PetscMalloc1(n, &s->modal_freq));

  /* the result file: one output per mode, without the contact points (no contact is solved) */
  s->contact      = NULL;
  s->output_every = 1;
  PetscCall(MBCSolverOutputOpen(s));
  PetscCall(PetscPrintf(s->comm, "Modal analysis of %s: %" PetscInt_FMT " modes (%s), mass-normalised; effective mass in %% of the total (x %.6e, y %.6e, z %.6e)\n", s->scene->filename, n, nmult ? "couples tied" : "bodies alone", (double)mtot[0], (double)mtot[1], (double)mtot[2]));
  PetscCall(PetscPrintf(s->comm, " mode  frequency [Hz]    period [s]   m_x %%   m_y %%   m_z %%   sum x   sum y   sum z\n"));
  {
    PetscReal cum[3] = {0, 0, 0};
    for (PetscInt i = 0; i < n; i++) {
      PetscScalar kr, mm;
      PetscCall(EPSGetEigenpair(eps, i, &kr, NULL, x, NULL));
      PetscCall(MatMult(B, x, Bx));
      PetscCall(VecDot(x, Bx, &mm));
      PetscCheck(PetscRealPart(mm) > 0, s->comm, PETSC_ERR_PLIB, "Modal analysis: mode %" PetscInt_FMT " has no mass", i + 1);
      PetscCall(VecScale(x, 1.0 / PetscSqrtReal(PetscRealPart(mm)))); /* phi^T M phi = 1 */
      PetscCall(VecScale(Bx, 1.0 / PetscSqrtReal(PetscRealPart(mm))));
      { /* a common sign: the largest component positive, so runs on other rank counts agree */
        PetscInt  imax;
        PetscReal vmax, vmin;
        PetscCall(VecMax(x, &imax, &vmax));
        PetscCall(VecMin(x, &imax, &vmin));
        if (-vmin > vmax * (1 + 1e-8)) {
          PetscCall(VecScale(x, -1.0));
          PetscCall(VecScale(Bx, -1.0));
        }
      }
      freq[i] = PetscRealPart(kr) > 0 ? PetscSqrtReal(PetscRealPart(kr)) / (2 * PETSC_PI) : 0.0;
      for (PetscInt d = 0; d < 3; d++) {
        PetscScalar g;
        PetscCall(VecDot(e[d], Bx, &g)); /* Gamma_d = phi^T M iota_d */
        gamma[3 * i + d] = PetscRealPart(g);
        meff[3 * i + d]  = PetscSqr(PetscRealPart(g));
        cum[d] += mtot[d] > 0 ? meff[3 * i + d] / mtot[d] : 0;
      }
      s->modal_freq[i] = freq[i];
      PetscCall(PetscPrintf(s->comm, "%5" PetscInt_FMT "  %14.6g  %12.6g  %6.2f  %6.2f  %6.2f  %6.2f  %6.2f  %6.2f\n", i + 1, (double)freq[i], freq[i] > 0 ? (double)(1 / freq[i]) : (double)INFINITY, mtot[0] > 0 ? (double)(100 * meff[3 * i] / mtot[0]) : 0.0, mtot[1] > 0 ? (double)(100 * meff[3 * i + 1] / mtot[1]) : 0.0, mtot[2] > 0 ? (double)(100 * meff[3 * i + 2] / mtot[2]) : 0.0, (double)(100 * cum[0]), (double)(100 * cum[1]), (double)(100 * cum[2])));
      PetscCall(ModalToBodies(s, &L, x));
      s->step = i + 1;
      s->time = freq[i];
      PetscCall(MBCSolverOutputStep(s));
    }
  }
  {
    PetscInt first = 0; /* the first elastic mode: rigid modes (free bodies) come out near 0 */
    while (first < n && freq[first] <= 1e-3 * freq[n - 1]) first++;
    if (first < n - 1 && freq[n - 1] > 1.001 * freq[first]) { /* a helper: 5 % at the first elastic and the last mode found */
      const PetscReal w1 = 2 * PETSC_PI * freq[first], w2 = 2 * PETSC_PI * freq[n - 1], z = 0.05;
      const PetscReal beta = 2 * z / (w1 + w2), alpha = beta * w1 * w2;
      PetscCall(PetscPrintf(s->comm, "Rayleigh damping of 5 %% at %g Hz and %g Hz: rayleigh_alpha %.6g, rayleigh_beta %.6g (mbcontact.records.rayleigh for others)\n", (double)freq[first], (double)freq[n - 1], (double)alpha, (double)beta));
    }
  }
  PetscCall(ModalWrite(s, n, freq, gamma, meff, mtot));
  PetscCall(MBCSolverOutputClose(s));
  s->contact = contact;
  PetscCall(PetscFree3(freq, gamma, meff));
  for (PetscInt d = 0; d < 3; d++) PetscCall(VecDestroy(&e[d]));
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&Bx));
  PetscCall(EPSDestroy(&eps));
  PetscCall(MatDestroy(&K));
  PetscCall(MatDestroy(&B));
  PetscCall(ModalLayoutDestroy(&L));
  PetscFunctionReturn(0);
}
