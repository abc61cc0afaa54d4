/* The multipliers of a step (the set-up and the distribution: interface.c): q from every body's
   free increment, the multiplier solve on the rows of each rank, dU += A^-1 H lambda; the
   points' states and the work of their forces; the FCLIB copy of a step's problem. */
#include <mbc/private/interfaceimpl.h>

/* -mbc_fclib_write FILE at step -mbc_fclib_write_step: the scaled problem (W = D / dscale,
   r = dscale lambda) and its solution as an FCLIB local problem in rank order, gathered to and
   written by rank 0. With bonded couples it is the shifted problem of the step's last solve
   (InterfaceSolveJoints): a bonded point's r is r_n + s (s = dscale (c/mu) A / theta), q is
   q - W s, its mu the couple's; a broken point's mu is mu_residual; the title says so. */
static PetscErrorCode InterfaceWriteFclib(MBCInterface ifc, PetscInt step)
{
  PetscMPIInt        rank;
  PetscInt           m = ifc->coff[ifc->ncontact];
  IS                 is;
  Mat               *W0;
  Vec                v[3], v0[3];
  VecScatter         sc;
  MBCFrictionProblem fp0;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(ifc->comm, &rank));
  PetscCall(ISCreateStride(PETSC_COMM_SELF, rank ? 0 : m, 0, 1, &is));
  PetscCall(MatCreateSubMatrices(ifc->fp.W, 1, &is, &is, MAT_INITIAL_MATRIX, &W0));
  PetscCall(ISDestroy(&is));
  v[0] = ifc->fp.q, v[1] = ifc->lambda, v[2] = ifc->ucontact;
  for (PetscInt i = 0; i < 3; i++) {
    PetscCall(VecScatterCreateToZero(v[i], &sc, &v0[i]));
    PetscCall(VecScatterBegin(sc, v[i], v0[i], INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(sc, v[i], v0[i], INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterDestroy(&sc));
  }
  if (!rank) {
    PetscInt *dims;
    PetscCall(PetscMemzero(&fp0, sizeof(fp0)));
    fp0.nc = ifc->ncontact;
    fp0.W  = W0[0];
    fp0.q  = v0[0];
    PetscCall(PetscMalloc2(fp0.nc + 1, &fp0.mu, fp0.nc + 1, &dims));
    for (PetscInt p = 0; p < fp0.nc; p++) {
      fp0.mu[p] = MBCInterfaceJointMu(ifc, ifc->order[p]);
      dims[p]   = ifc->poff[p + 1] - ifc->poff[p];
    }
    PetscCall(MBCFrictionProblemSetBlocks(&fp0, dims));
    PetscCall(PetscSNPrintf(fp0.title, sizeof(fp0.title), "%s, step %" PetscInt_FMT, ifc->scene->filename, step));
    if (MBCInterfaceJointBonded(ifc)) PetscCall(PetscSNPrintf(fp0.description, sizeof(fp0.description), "mbcontact bonded joints: %" PetscInt_FMT " bonded points: the shifted cone, their r_n = r_n(contact) + s with s = dscale (c/mu) A / theta (the apex force), q = q(contact) - W s (the other points as they are; broken points have mu_residual); the contact force is r - s", MBCInterfaceJointBonded(ifc)));
    PetscCall(MBCFclibWriteLocal(ifc->fclib_file, &fp0, v0[1], v0[2]));
    PetscCall(PetscFree(fp0.off));
    PetscCall(PetscFree2(fp0.mu, dims));
  }
  for (PetscInt i = 0; i < 3; i++) PetscCall(VecDestroy(&v0[i]));
  PetscCall(MatDestroySubMatrices(1, &W0));
  PetscCallMPI(MPI_Barrier(ifc->comm));
  PetscFunctionReturn(0);
}

/* Convex hull (counter-clockwise, Andrew's monotone chain) of n points p (2 each, sorted here);
   returns its vertex count, written to h (room for n + 1). */
static PetscInt Hull2D(PetscInt n, PetscReal p[], PetscReal h[])
{
  PetscInt k = 0;

  for (PetscInt i = 1; i < n; i++) /* insertion sort by (x, y): patches are small */
    for (PetscInt j = i; j > 0 && (p[2 * j] < p[2 * j - 2] || (p[2 * j] == p[2 * j - 2] && p[2 * j + 1] < p[2 * j - 1])); j--) {
      PetscReal t0 = p[2 * j], t1 = p[2 * j + 1];
      p[2 * j] = p[2 * j - 2], p[2 * j + 1] = p[2 * j - 1], p[2 * j - 2] = t0, p[2 * j - 1] = t1;
    }
#define CROSS(o, a, b) (((a)[0] - (o)[0]) * ((b)[1] - (o)[1]) - ((a)[1] - (o)[1]) * ((b)[0] - (o)[0]))
  for (PetscInt i = 0; i < n; i++) {
    while (k >= 2 && CROSS(h + 2 * k - 4, h + 2 * k - 2, p + 2 * i) <= 0) k--;
    h[2 * k] = p[2 * i], h[2 * k + 1] = p[2 * i + 1], k++;
  }
  for (PetscInt i = n - 2, lo = k + 1; i >= 0; i--) {
    while (k >= lo && CROSS(h + 2 * k - 4, h + 2 * k - 2, p + 2 * i) <= 0) k--;
    h[2 * k] = p[2 * i], h[2 * k + 1] = p[2 * i + 1], k++;
  }
#undef CROSS
  return k > 1 ? k - 1 : k;
}

/* A body held only by contact on one plane (nrigid 6, coplanar contact nodes and normals): its
   contact pressures are >= 0, so their resultant acts inside the contact area. The load's
   resultant meets the plane at c = O + (nu x M_O) / (F . nu) (moment balance normal to nu;
   friction acts in the plane and has no moment there): outside the convex hull of the body's
   contact nodes the body overturns, an input error named here. Other shapes are not judged. */
static PetscErrorCode InterfaceOverturning(MBCInterface ifc, PetscInt b, const PetscReal F[3], const PetscReal M[3], const PetscReal nu[3], PetscInt step, PetscReal time)
{
  MBCContact c = ifc->contact;
  PetscReal *x, *p2, *h, O[3] = {0, 0, 0}, t1[3], t2[3], MO[3], cp[3], fn, diam = 0, out = -PETSC_MAX_REAL;
  PetscInt   n = 0, nmax = 0, nh;

  PetscFunctionBegin;
  for (PetscInt k = 0; k < ifc->ncontact; k++) {
    const MBCCouple *cpl = &c->couples[ifc->kcouple[k]];
    const PetscInt   j   = ifc->kpoint[k];
    nmax += cpl->moff[j + 1] - cpl->moff[j] + cpl->soff[j + 1] - cpl->soff[j];
    if (MBCInterfacePointTouches(cpl, j, b) && PetscAbsReal(MBCDot(&ifc->frames[9 * k], nu)) < 1 - 1e-8) PetscFunctionReturn(0); /* curved */
  }
  PetscCall(PetscMalloc3(3 * nmax + 3, &x, 2 * nmax + 2, &p2, 2 * nmax + 4, &h));
  for (PetscInt k = 0; k < ifc->ncontact; k++) { /* the body's nodes of its contact points, reference coordinates */
    const MBCCouple *cpl = &c->couples[ifc->kcouple[k]];
    const PetscInt   j   = ifc->kpoint[k];
    for (PetscInt l = cpl->moff[j]; l < cpl->moff[j + 1]; l++)
      if (cpl->master.nbody[cpl->mnode[l]] == b) PetscCall(PetscArraycpy(x + 3 * n++, cpl->master.x0 + 3 * cpl->mnode[l], 3));
    for (PetscInt l = cpl->soff[j]; l < cpl->soff[j + 1]; l++)
      if (cpl->slave.nbody[cpl->snode[l]] == b) PetscCall(PetscArraycpy(x + 3 * n++, cpl->slave.x0 + 3 * cpl->snode[l], 3));
  }
  for (PetscInt i = 0; i < n; i++)
    for (PetscInt d = 0; d < 3; d++) O[d] += x[3 * i + d] / n;
  for (PetscInt i = 0; i < n; i++) {
    PetscReal r[3];
    MBCSub(x + 3 * i, O, r);
    diam = PetscMax(diam, PetscSqrtReal(MBCDot(r, r)));
  }
  { /* t1, t2: a basis of the plane */
    PetscReal e[3] = {0, 0, 0};
    e[PetscAbsReal(nu[0]) < 0.6 ? 0 : 1] = 1;
    MBCCross(nu, e, t1);
    MBCNormalize(t1);
    MBCCross(nu, t1, t2);
  }
  for (PetscInt i = 0; i < n; i++) {
    PetscReal r[3];
    MBCSub(x + 3 * i, O, r);
    if (PetscAbsReal(MBCDot(r, nu)) > 1e-6 * diam) { /* not one plane */
      PetscCall(PetscFree3(x, p2, h));
      PetscFunctionReturn(0);
    }
    p2[2 * i] = MBCDot(r, t1), p2[2 * i + 1] = MBCDot(r, t2);
  }
  nh = Hull2D(n, p2, h);
  fn = MBCDot(F, nu);
  MBCCross(O, F, MO); /* the load's moment about O: M - O x F */
  for (PetscInt d = 0; d < 3; d++) MO[d] = M[d] - MO[d];
  if (nh >= 3 && fn != 0) {
    PetscReal q[2], nxm[3], r[3];
    MBCCross(nu, MO, nxm);
    for (PetscInt d = 0; d < 3; d++) cp[d] = O[d] + nxm[d] / fn;
    MBCSub(cp, O, r);
    q[0] = MBCDot(r, t1), q[1] = MBCDot(r, t2);
    for (PetscInt i = 0; i < nh; i++) { /* distance outside the edge i -> i + 1 (counter-clockwise) */
      const PetscReal *a = h + 2 * i, *e = h + 2 * ((i + 1) % nh);
      const PetscReal  l = PetscSqrtReal(PetscSqr(e[0] - a[0]) + PetscSqr(e[1] - a[1]));
      out                = PetscMax(out, -((e[0] - a[0]) * (q[1] - a[1]) - (e[1] - a[1]) * (q[0] - a[0])) / l);
    }
  }
  PetscCall(PetscFree3(x, p2, h));
  PetscCheck(!(out > 1e-6 * diam), ifc->comm, PETSC_ERR_NOT_CONVERGED, "Static step %" PetscInt_FMT " (t = %g): no static equilibrium: body '%s' overturns: its load's resultant (%g normal to its contact plane) meets that plane at (%g, %g, %g), %g outside its contact area (the convex hull of its contact nodes, extent %g); contact pressures can only push, so a static state needs the resultant inside the contact area: lower the load, prescribe a displacement that holds the body, or run a dynamic analysis", step, (double)time, ifc->scene->bodies[b].name, (double)PetscAbsReal(fn), (double)cp[0], (double)cp[1], (double)cp[2], (double)out, (double)(2 * diam));
  PetscFunctionReturn(0);
}

/* A static contact solve with free bodies that failed: is the load on some free body beyond
   what friction can hold, or does it overturn it? Per body its load's resultant F (this
   step's), the mean normal n of the contact points that touch it and the largest mu of its
   couples: a tangential load |F - (F.n) n| above mu |F.n| has no static equilibrium, an input
   error named here; so has a body held only by contact whose load's resultant acts outside its
   contact area (InterfaceOverturning). */
static PetscErrorCode InterfaceFrictionCapacity(MBCInterface ifc, PetscInt step, PetscReal time)
{
  MBCContact c = ifc->contact;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    PetscReal F[8] = {0, 0, 0, 0, 0, 0, 0, 0}, n[3] = {0, 0, 0}, mu = 0, fn = 0, ft[3], T = 0, N, cA = 0;
    PetscInt  cnt = 0;
    if (ifc->bodies[b]) { /* F, its moment and whether the body is free (held only by contact), from its first rank */
      PetscMPIInt      brank;
      MPI_Comm         bcomm;
      PetscInt         nr;
      const PetscReal *fres;
      PetscCall(MBCBodyGetComm(ifc->bodies[b], &bcomm));
      PetscCallMPI(MPI_Comm_rank(bcomm, &brank));
      PetscCall(MBCBodyGetRigidModes(ifc->bodies[b], &nr, NULL));
      PetscCall(MBCBodyGetRigidEquilibrium(ifc->bodies[b], NULL, NULL, NULL, &fres));
      if (!brank && nr) {
        for (PetscInt d = 0; d < 3; d++) F[d] = fres[d], F[4 + d] = fres[3 + d];
        F[3] = 1;
        F[7] = nr == 6;
      }
    }
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, F, 8, MPIU_REAL, MPIU_SUM, ifc->comm));
    if (!F[3]) continue;
    for (PetscInt k = 0; k < ifc->ncontact; k++) { /* the points touching b (replicated bookkeeping) */
      const MBCCouple *cp = &c->couples[ifc->kcouple[k]];
      const PetscInt   j  = ifc->kpoint[k];
      if (!MBCInterfacePointTouches(cp, j, b)) continue;
      for (PetscInt d = 0; d < 3; d++) n[d] += ifc->frames[9 * k + d];
      mu = PetscMax(mu, MBCInterfaceJointMu(ifc, k)); /* a broken bond's mu_residual */
      if (MBCInterfaceJointPoint(ifc, ifc->kcouple[k], j, NULL) == 1) cA += ifc->scene->couples[ifc->kcouple[k]].cohesion * cp->points[j].area; /* a bond's cohesion holds too */
      cnt++;
    }
    N = PetscSqrtReal(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!cnt || !(N > 0)) continue;
    for (PetscInt d = 0; d < 3; d++) n[d] /= N, fn += F[d] * n[d];
    for (PetscInt d = 0; d < 3; d++) ft[d] = F[d] - fn * n[d], T += ft[d] * ft[d];
    T = PetscSqrtReal(T);
    PetscCheck(!(cA > 0 && T > mu * PetscAbsReal(fn) + cA), ifc->comm, PETSC_ERR_NOT_CONVERGED, "Static step %" PetscInt_FMT " (t = %g): no static equilibrium: body '%s' carries a tangential load of %g against a capacity mu N + c A_bonded = %g x %g + %g = %g on its contact surfaces (its bonds broken so far: mu_residual; T / capacity = %.4f); lower the load, or run a dynamic analysis", step, (double)time, ifc->scene->bodies[b].name, (double)T, (double)mu, (double)PetscAbsReal(fn), (double)cA, (double)(mu * PetscAbsReal(fn) + cA), (double)(T / (mu * PetscAbsReal(fn) + cA)));
    if (cA > 0) continue; /* within the bonded capacity: the generic message, or a cut */
    PetscCheck(!(T > mu * PetscAbsReal(fn)), ifc->comm, PETSC_ERR_NOT_CONVERGED, "Static step %" PetscInt_FMT " (t = %g): no static equilibrium: body '%s' carries a tangential load of %g along (%.3f, %.3f, %.3f) against a friction capacity mu N = %g x %g = %g on its contact surfaces (T / mu N = %.4f); a static state needs T <= mu N: lower the load, prescribe a displacement that holds the body, or run a dynamic analysis", step, (double)time, ifc->scene->bodies[b].name, (double)T, (double)(ft[0] / T), (double)(ft[1] / T), (double)(ft[2] / T), (double)mu, (double)PetscAbsReal(fn), (double)(mu * PetscAbsReal(fn)), (double)(T / (mu * PetscAbsReal(fn))));
    if (F[7]) PetscCall(InterfaceOverturning(ifc, b, F, F + 4, n, step, time));
  }
  PetscFunctionReturn(0);
}

/* The multiplier solve of fp with q scaled to unit norm: the FCLIB merit |r - proj(..)| / (1 + |q|)
   then is relative, and -mbc_pgs_rtol means the same in m or mm (absolute in the scene's length
   unit, 1e-8 would be 10 nm in m and 10 pm in mm). shift (bonded couples, else NULL): the problem
   is in r' = r + shift, so the free bodies' equilibrium G r = e becomes G r' = e + G shift. */
static PetscErrorCode InterfaceSolveScaled(MBCInterface ifc, PetscInt step, PetscReal time, Vec shift, PetscReal *qnorm)
{
  PetscReal L;

  PetscFunctionBegin;
  PetscCall(VecNorm(ifc->fp.q, NORM_2, &L));
  *qnorm = L;
  if (!(L > 0)) L = 1;
  PetscCall(MBCInterfaceRigidRHS(ifc, step, time));
  if (shift && ifc->fp.G) PetscCall(MatMultAdd(ifc->fp.G, shift, ifc->fp.e, ifc->fp.e));
  if (ifc->fp.G) PetscCall(VecZeroEntries(ifc->fp.alpha)); /* the rigid motion of this increment */
  PetscCall(VecScale(ifc->fp.q, 1 / L));
  PetscCall(VecScale(ifc->lambda, 1 / L));
  if (ifc->fp.G) {
    PetscCall(VecScale(ifc->fp.e, 1 / L));
    PetscCall(VecScale(ifc->fp.alpha, 1 / L));
  }
  PetscCall(MBCMultiplierSetProblem(ifc->mult, &ifc->fp));
  PetscCall(MBCMultiplierSolve(ifc->mult, ifc->lambda, ifc->ucontact)); /* warm start: r of the last step */
  PetscCall(VecScale(ifc->fp.q, L));
  PetscCall(VecScale(ifc->lambda, L));
  PetscCall(VecScale(ifc->ucontact, L));
  if (ifc->fp.G) {
    PetscCall(VecScale(ifc->fp.e, L));
    PetscCall(VecScale(ifc->fp.alpha, L));
  }
  PetscFunctionReturn(0);
}

/* Bonded couples (interfacejoint.c): the bonded cone is the Coulomb cone shifted along the normal
   by s, so the multiplier problem in r' = r + s is the solvers' own, with q' = q - W s (one product
   with W). After each solve the bonded points whose traction reached the cone's boundary break,
   and the changed problem (their shift gone, mu_residual) is solved again, until no point breaks:
   points only break, so the cascade ends within the points' count. A failed solve undoes the
   breaks of this call (the caller cuts the step). The FCLIB copy is the last solve's shifted
   problem. */
static PetscErrorCode InterfaceSolveJoints(MBCInterface ifc, PetscInt step, PetscReal time, PetscBool may_fail, PetscReal *qnorm)
{
  Vec             q0, s;
  PetscInt        nnew, total = 0, nsolves = 0;
  const PetscBool soft = MBCInterfaceHasSoftening(ifc);

  PetscFunctionBegin;
  PetscCall(VecDuplicate(ifc->fp.q, &q0));
  PetscCall(VecCopy(ifc->fp.q, q0));
  PetscCall(VecDuplicate(ifc->lambda, &s));
  for (;;) {
    PetscCall(MBCInterfaceJointProblem(ifc, s));
    PetscCall(MatMult(ifc->fp.W, s, ifc->ucontact));
    PetscCall(VecWAXPY(ifc->fp.q, -1.0, ifc->ucontact, q0));
    { /* the warm start in r'; from no contact force at all r' = 0, so that the multiplier solve
         starts as from scratch (the Newton type's all-stick predictor with free bodies) */
      PetscReal lmax;
      PetscCall(VecNorm(ifc->lambda, NORM_INFINITY, &lmax));
      if (lmax > 0) PetscCall(VecAXPY(ifc->lambda, 1.0, s));
    }
    PetscCall(InterfaceSolveScaled(ifc, step, time, s, qnorm));
    nsolves++;
    if (ifc->fclib_step == step && ifc->fclib_file[0]) PetscCall(InterfaceWriteFclib(ifc, step));
    PetscCall(VecAXPY(ifc->lambda, -1.0, s));
    if (ifc->mult->reason < 0) break;
    PetscCall(MBCInterfaceGather(ifc, ifc->lambda, ifc->rall));
    PetscCall(MBCInterfaceJointBreak(ifc, time, &nnew));
    if (soft) { /* the damage of the softening bonds from this solve's relative displacements: a fixed point in D */
      PetscInt  ns;
      PetscReal dmax;
      PetscCall(MBCInterfaceGather(ifc, ifc->ucontact, ifc->uall));
      PetscCall(MBCInterfaceJointSoften(ifc, time, &ns, &dmax));
      total += nnew + ns;
      if (!nnew && !ns && dmax <= ifc->jtol) break;
      if (nsolves >= 200) { /* a bond near its snap-back can creep: say so, keep the last state */
        PetscCall(PetscInfo(NULL, "step %" PetscInt_FMT " (t = %g): the softening bonds' damage still changed by %g after %" PetscInt_FMT " solves\n", step, (double)time, (double)dmax, nsolves));
        break;
      }
      continue;
    }
    if (!nnew) break;
    total += nnew;
  }
  if (ifc->mult->reason < 0 && may_fail) { /* the step is cut: its breaks and damage are undone */
    PetscCall(MBCInterfaceJointUnbreak(ifc, time));
    PetscCall(MBCInterfaceJointCommit(ifc, PETSC_FALSE));
  } else if (soft && ifc->analysis != MBC_ANALYSIS_STATIC) PetscCall(MBCInterfaceJointCommit(ifc, PETSC_TRUE)); /* a static load step's damage counts from its start, committed when the next begins */
  if (total) PetscCall(PetscInfo(NULL, "step %" PetscInt_FMT " (t = %g): %" PetscInt_FMT " bonds broke, %" PetscInt_FMT " multiplier solves\n", step, (double)time, total, nsolves));
  ifc->jbroke = ifc->mult->reason < 0 && may_fail ? 0 : total, ifc->jsolves = nsolves;
  PetscCall(VecCopy(q0, ifc->fp.q));
  PetscCall(VecDestroy(&q0));
  PetscCall(VecDestroy(&s));
  PetscFunctionReturn(0);
}

/* Coulomb's law in a static load step holds for the slip over the whole load step: the
   equilibrium iterations after the first only correct it, so their tangential rates start from
   the slip the load step's earlier iterations made (else a point that slid in the first iteration
   and not in the next would be taken to stick, its traction inside the cone while the block
   slides). A load step is the output step, or a half of it where a cut made two. */
static PetscErrorCode InterfaceAddStepSlip(MBCInterface ifc, Vec q)
{
  PetscScalar *a;
  PetscInt     rstart;

  PetscFunctionBegin;
  PetscCall(VecGetOwnershipRange(q, &rstart, NULL));
  PetscCall(VecGetArray(q, &a));
  for (PetscInt p = ifc->pfirst; p < ifc->plast; p++) {
    const PetscInt k = ifc->order[p];
    if (ifc->coff[k + 1] - ifc->coff[k] == 3)
      for (PetscInt d = 1; d < 3; d++) a[ifc->poff[p] + d - rstart] += ifc->stepslip[3 * k + d] - ifc->cutslip[3 * k + d];
  }
  PetscCall(VecRestoreArray(q, &a));
  PetscFunctionReturn(0);
}

/* A step (of the output: a static load step, a dynamic step with its cut steps) begins: the slip
   its states are decided by counts from here. */
PetscErrorCode MBCInterfaceStepBegin(MBCInterface ifc)
{
  PetscFunctionBegin;
  if (ifc->stepslip) PetscCall(PetscArrayzero(ifc->stepslip, 3 * ifc->ncontact));
  if (ifc->cutslip) PetscCall(PetscArrayzero(ifc->cutslip, 3 * ifc->ncontact));
  ifc->stepres = ifc->cutres = 0;
  PetscFunctionReturn(0);
}

/* A static load step (the step, or a half of it after a cut) begins: Coulomb's law counts its
   slip from here. */
PetscErrorCode MBCInterfaceLoadStepBegin(MBCInterface ifc)
{
  PetscFunctionBegin;
  if (ifc->cutslip) PetscCall(PetscArraycpy(ifc->cutslip, ifc->stepslip, 3 * ifc->ncontact));
  ifc->cutres = ifc->stepres;
  PetscCall(MBCInterfaceJointSave(ifc, PETSC_FALSE));
  PetscCall(MBCInterfaceJointCommit(ifc, PETSC_TRUE)); /* the softening bonds' damage of the load step before */
  PetscFunctionReturn(0);
}

/* A static load step is abandoned (to be cut): the slip it made and its breaks are undone. */
PetscErrorCode MBCInterfaceStepAbandon(MBCInterface ifc)
{
  PetscFunctionBegin;
  for (PetscInt i = 0; ifc->stepslip && i < 3 * ifc->ncontact; i++) {
    ifc->slip[i] -= ifc->stepslip[i] - ifc->cutslip[i];
    ifc->stepslip[i] = ifc->cutslip[i];
  }
  ifc->stepres = ifc->cutres;
  PetscCall(MBCInterfaceJointSave(ifc, PETSC_TRUE)); /* and the bonds it broke */
  PetscCall(MBCInterfaceJointCommit(ifc, PETSC_FALSE)); /* and the damage it did */
  PetscFunctionReturn(0);
}

/* Given every body's free increment du, solves for the multipliers of step `step`
   (ending at `time`) and adds A^-1 H lambda. A solve that may fail (the caller can cut the step)
   and does returns *failed with nothing changed; otherwise a failed solve is an error. */
PetscErrorCode MBCInterfaceSolve(MBCInterface ifc, PetscInt step, PetscReal time, PetscBool may_fail, PetscBool *failed)
{
  const PetscInt nc = ifc->ncontact;
  PetscReal      qnorm = 0; /* |q|, the step's free motion at the contact points */

  PetscFunctionBegin;
  *failed = PETSC_FALSE;
  if (!nc) PetscFunctionReturn(0);
  if (may_fail) { /* the warm start, for a retry with a smaller step */
    if (!ifc->lamsave) PetscCall(VecDuplicate(ifc->lambda, &ifc->lamsave)); /* freed with the layout it has */
    PetscCall(VecCopy(ifc->lambda, ifc->lamsave));
  }
  PetscCall(MBCInterfaceGapRate(ifc, ifc->fp.q));
  if (ifc->analysis == MBC_ANALYSIS_STATIC) PetscCall(InterfaceAddStepSlip(ifc, ifc->fp.q));
  if (ifc->carry != 0) { /* q' = q - c D lambda_n (scaled: W = D / dscale) */
    Vec t;
    PetscCall(VecDuplicate(ifc->lamprev, &t));
    PetscCall(VecAXPBY(t, ifc->dscale, 0.0, ifc->lamprev));
    PetscCall(MatMult(ifc->fp.W, t, ifc->ucontact));
    PetscCall(VecAXPY(ifc->fp.q, -ifc->carry, ifc->ucontact));
    PetscCall(VecDestroy(&t));
  }
  if (MBCInterfaceHasJoints(ifc)) PetscCall(InterfaceSolveJoints(ifc, step, time, may_fail, &qnorm));
  else {
    PetscCall(InterfaceSolveScaled(ifc, step, time, NULL, &qnorm));
    if (ifc->fclib_step == step && ifc->fclib_file[0]) PetscCall(InterfaceWriteFclib(ifc, step));
  }
  if (ifc->mult->reason < 0 && ifc->fp.G) PetscCall(InterfaceFrictionCapacity(ifc, step, time));
  if (ifc->mult->reason < 0 && may_fail) { /* the caller cuts the step: nothing changed */
    PetscCall(VecCopy(ifc->lamsave, ifc->lambda));
    *failed = PETSC_TRUE;
    PetscFunctionReturn(0);
  }
  PetscCheck(ifc->mult->reason > 0, ifc->comm, PETSC_ERR_NOT_CONVERGED, "Contact multipliers at step %" PetscInt_FMT " (t = %g): %s solve %s after %" PetscInt_FMT " iterations, FCLIB merit %g > -mbc_multiplier_rtol %g", step, (double)time, ((PetscObject)ifc->mult)->type_name, MBCMultiplierConvergedReasonName(ifc->mult->reason), ifc->mult->its, (double)ifc->mult->merit, (double)ifc->mult->rtol);
  PetscCall(VecAXPBY(ifc->lamprev, 1.0 / ifc->dscale, -ifc->carry, ifc->lambda)); /* lambda_n+1 = r - c lambda_n (physical) */
  PetscCall(MBCInterfaceGather(ifc, ifc->lambda, ifc->rall));
  PetscCall(MBCInterfaceGather(ifc, ifc->ucontact, ifc->uall));
  /* u = D lambda_n+1 + H^T du_free (+ gap) is H^T du: its tangential part is the slip of this
     solve (H's master weight is 1, so in length units); in a static step it counts from the step's
     start (InterfaceAddStepSlip), and this iteration moved the points by u_t - stepslip; a dynamic
     step's cut steps add theirs up */
  for (PetscInt k = 0; k < nc; k++)
    if (ifc->coff[k + 1] - ifc->coff[k] == 3)
      for (PetscInt d = 1; d < 3; d++) {
        const PetscReal u = ifc->uall[ifc->coff[k] + d], before = ifc->analysis == MBC_ANALYSIS_STATIC ? ifc->stepslip[3 * k + d] - ifc->cutslip[3 * k + d] : 0;
        ifc->slip[3 * k + d] += u - before;
        ifc->stepslip[3 * k + d] += u - before;
      }
  /* what the solve resolves of it: at most 2 rtol |q| of u_t at a sticking point (the merit's bound, MBCInterfaceStates) */
  ifc->stepres = (ifc->analysis == MBC_ANALYSIS_STATIC ? ifc->cutres : ifc->stepres) + 2 * ifc->mult->rtol * qnorm;
  PetscCall(MBCInterfaceToBodies(ifc, ifc->lamprev));
  for (PetscInt b = 0; b < ifc->nbodies; b++) {
    MBCBody body = ifc->bodies[b];
    Mat     Ainv;
    if (!body || !ifc->H[b]) continue;
    PetscCall(MatMult(ifc->H[b], ifc->lam[b], ifc->Hl[b]));
    PetscCall(MBCBodyGetInverse(body, &Ainv));
    PetscCall(MatMult(Ainv, ifc->Hl[b], ifc->Xl[b]));
    PetscCall(MBCBodyAddIncrement(body, ifc->Xl[b]));
  }
  if (ifc->fp.G) PetscCall(MBCInterfaceRigidMotion(ifc));
  PetscFunctionReturn(0);
}

/* Per contact point (in couple order): its state in the step and the step's mean contact force
   z = theta r (in the frame n, t1, t2; tangents 0 where frictionless); counts of each state.
   state and lambda may be NULL. The same on every rank. The state is what the point did in the
   step (docs/design.md, "A point's state"): separated where it carries no normal force (its gap
   open), else slip where its slip in the step (stepslip: over the static step's iterations, or
   the dynamic step's cut steps) exceeds what the multiplier solves resolve of it, stick where it
   does not (its traction then lies in the cone, or on it about to slip). The merit's bound, |u_t|
   <= 2 rtol |q| at a sticking point (the natural map's residual there is u_t; the merit is it over
   1 + sqrt|q| with |q| scaled to 1), summed over the step's solves, is that resolution (stepres);
   a frictionless point in contact is "slip"; a bonded point (interfacejoint.c) is never separated,
   its bond holding it in tension too. (The state used to be read from the traction, inside
   the cone by 1e-6 or not: points that slid in the step with their mean force inside the cone, a
   reversal or the trapezoidal rule's period-2 oscillation, were "stick".) */
PetscErrorCode MBCInterfaceStates(MBCInterface ifc, PetscInt count[3], PetscInt state[], PetscReal lambda[])
{
  MBCContact c = ifc->contact;

  PetscFunctionBegin;
  count[0] = count[1] = count[2] = 0;
  if (!ifc->ncontact) PetscFunctionReturn(0);
  for (PetscInt i = 0, k = 0; i < c->ncouples; i++)
    for (PetscInt j = 0; j < c->couples[i].npoints; j++, k++) {
      const PetscInt o = ifc->coff[k], dim = ifc->coff[k + 1] - o;
      PetscReal      lam[3] = {0, 0, 0};
      PetscInt       st;
      for (PetscInt d = 0; d < dim; d++) lam[d] = ifc->held[k] & (1 << d) ? 0 : ifc->theta * ifc->rall[o + d] / ifc->dscale; /* a held direction's r acts on no body */
      if (!(lam[0] > 0) && MBCInterfaceJointPoint(ifc, i, j, NULL) != 1) st = MBC_CONTACT_SEPARATED; /* a bond holds in tension, or unloaded: not separated */
      else if (dim == 3 && PetscSqrtReal(PetscSqr(ifc->stepslip[3 * k + 1]) + PetscSqr(ifc->stepslip[3 * k + 2])) <= ifc->stepres) st = MBC_CONTACT_STICK;
      else st = MBC_CONTACT_SLIP;
      count[st]++;
      if (state) state[k] = st;
      if (lambda)
        for (PetscInt d = 0; d < 3; d++) lambda[3 * k + d] = lam[d];
    }
  PetscFunctionReturn(0);
}

/* Work of the step's mean contact force z on the bodies, z . H^T du per point, added to
   *wfriction (tangential) and *wcontact (normal): u = D lambda_n+1 + q is (g_n, 0, 0) + H^T du
   (g_n the gap the step started from, MBCInterfaceStartGap: the search comes after the step), in the
   frames the multipliers live in; friction dissipates -z_t . du_t >= 0, the normal contact takes
   -z_n (g_n+1 - g_n) = z_n g_n >= 0 where complementarity holds. The trapezoidal rule's energy
   balance holds with the step's mean force, so with these the total is conserved to the
   multiplier tolerance. Replicated data (couple order): the same on every rank. */
void MBCInterfaceContactWork(MBCInterface ifc, PetscReal *wfriction, PetscReal *wcontact)
{
  for (PetscInt k = 0; k < ifc->ncontact; k++) {
    const PetscInt o = ifc->coff[k], dim = ifc->coff[k + 1] - o;
    const PetscReal g = MBCInterfaceStartGap(ifc, k); /* the gap the step started from */
    for (PetscInt d = 0; d < dim; d++) {
      const PetscReal z = ifc->theta * ifc->rall[o + d] / ifc->dscale, du = ifc->uall[o + d] - (d ? 0 : g);
      if (d) *wfriction -= z * du;
      else *wcontact -= z * du;
    }
  }
}
