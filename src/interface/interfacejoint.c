/* The joint law of bonded couples (docs/dam.md, "Bonded joints"): per master node of a couple
   with cohesion c > 0, its bond's state (bonded, or the time it broke: brittle, for good). A
   bonded point's traction lies in |t| <= c + mu p, p >= -f_t (f_t <= c/mu). With the apex
   s = c/mu times the point's area A this is the Coulomb cone shifted along the normal,
   r_n' = r_n + s: u = W r + q = W r' + (q - W s), so the bonded problem is the multiplier
   solve's own problem in r' (the solvers are untouched). A point whose traction the solve puts on
   the cone's boundary (slip, or the tension cut-off p = -f_t) breaks; the problem then changes
   (no shift, mu_residual) and is solved again until no point breaks (MBCInterfaceSolve). The
   break times (and a softening bond's damage, MBCInterfaceJointSoften) are this module's state;
   the interface keeps them per (couple, master node), which the re-search and the rebuilds of H
   keep, and the checkpoint carries them. */
#include <mbc/private/interfaceimpl.h>

/* A couple's scene description (the contact's couples are the scene's, in its order). */
static inline const MBCCoupleDesc *JointDesc(MBCInterface ifc, PetscInt i)
{
  return &ifc->scene->couples[i];
}

PetscBool MBCInterfaceHasJoints(MBCInterface ifc)
{
  if (!ifc) return PETSC_FALSE;
  for (PetscInt i = 0; i < ifc->scene->ncouples; i++)
    if (JointDesc(ifc, i)->cohesion > 0) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* The arrays of break times, every bond intact (PETSC_MAX_REAL), and the softening couples' damage
   and slip (0): made at the first use. */
static PetscErrorCode JointSetUp(MBCInterface ifc)
{
  MBCContact c = ifc->contact;

  PetscFunctionBegin;
  if (ifc->jbreak) PetscFunctionReturn(0);
  PetscCall(PetscCalloc3(c->ncouples, &ifc->jbreak, c->ncouples, &ifc->jsave, c->ncouples, &ifc->jsoft));
  for (PetscInt i = 0; i < c->ncouples; i++) {
    const PetscInt n = c->couples[i].master.nnodes;
    if (!(JointDesc(ifc, i)->cohesion > 0)) continue;
    PetscCall(PetscMalloc2(n + 1, &ifc->jbreak[i], n + 1, &ifc->jsave[i]));
    for (PetscInt m = 0; m <= n; m++) ifc->jbreak[i][m] = ifc->jsave[i][m] = PETSC_MAX_REAL;
    if (JointDesc(ifc, i)->softening > 0) PetscCall(PetscCalloc1(4 * n + 4, &ifc->jsoft[i]));
  }
  PetscFunctionReturn(0);
}

/* -mbc_joint_break_rtol, -mbc_joint_break_fraction (the solver's options) */
PetscErrorCode MBCInterfaceSetJointBreak(MBCInterface ifc, PetscReal tol, PetscReal frac)
{
  PetscFunctionBegin;
  ifc->jtol  = tol;
  ifc->jfrac = frac;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCInterfaceJointDestroy(MBCInterface ifc)
{
  PetscFunctionBegin;
  if (!ifc->jbreak) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < ifc->contact->ncouples; i++) {
    PetscCall(PetscFree2(ifc->jbreak[i], ifc->jsave[i]));
    PetscCall(PetscFree(ifc->jsoft[i]));
  }
  PetscCall(PetscFree3(ifc->jbreak, ifc->jsave, ifc->jsoft));
  PetscFunctionReturn(0);
}

/* Point j of couple i: bonded (1), broken (0), or on an unbonded couple (-1); *tbreak the time it broke (NaN if it did not). */
PetscInt MBCInterfaceJointPoint(MBCInterface ifc, PetscInt i, PetscInt j, PetscReal *tbreak)
{
  const PetscReal *jb = ifc->jbreak ? ifc->jbreak[i] : NULL;
  PetscReal        t;

  if (tbreak) *tbreak = NAN;
  if (!(JointDesc(ifc, i)->cohesion > 0)) return -1;
  t = jb ? jb[ifc->contact->couples[i].points[j].master] : PETSC_MAX_REAL;
  if (t == PETSC_MAX_REAL) return 1;
  if (tbreak) *tbreak = t;
  return 0;
}

PetscBool MBCInterfaceHasSoftening(MBCInterface ifc)
{
  if (!ifc) return PETSC_FALSE;
  for (PetscInt i = 0; i < ifc->scene->ncouples; i++)
    if (JointDesc(ifc, i)->cohesion > 0 && JointDesc(ifc, i)->softening > 0) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* Point j of couple i: its damage D (softening: the bond's strength is (1 - D) of the intact one's),
   0 while a brittle bond holds, 1 once broken; 0 on an unbonded couple. */
PetscReal MBCInterfaceJointDamage(MBCInterface ifc, PetscInt i, PetscInt j)
{
  const PetscInt b = MBCInterfaceJointPoint(ifc, i, j, NULL);
  if (b < 0) return 0;
  if (!b) return 1;
  return ifc->jsoft && ifc->jsoft[i] ? ifc->jsoft[i][4 * ifc->contact->couples[i].points[j].master] : 0;
}

/* The friction coefficient of point k (couple order): the couple's mu, mu_residual once broken,
   in between while it softens (mu + D (mu_r - mu)). */
PetscReal MBCInterfaceJointMu(MBCInterface ifc, PetscInt k)
{
  const PetscInt  i = ifc->kcouple[k], b = MBCInterfaceJointPoint(ifc, i, ifc->kpoint[k], NULL);
  const PetscReal mu = ifc->contact->couples[i].mu;
  if (b < 0) return mu;
  if (!b) return JointDesc(ifc, i)->mu_residual;
  return mu + MBCInterfaceJointDamage(ifc, i, ifc->kpoint[k]) * (JointDesc(ifc, i)->mu_residual - mu);
}

/* Bonded points among the points of the last build (for the monitor and the CSV). */
PetscInt MBCInterfaceJointBonded(MBCInterface ifc)
{
  PetscInt n = 0;
  for (PetscInt k = 0; k < ifc->ncontact; k++) n += MBCInterfaceJointPoint(ifc, ifc->kcouple[k], ifc->kpoint[k], NULL) == 1;
  return n;
}

/* The apex shift of point k in the units of r (scaled, r = dscale z / theta): the cone on the
   step's mean force z is |z_t| <= mu (z_n + (c/mu) A). */
static PetscReal JointShift(MBCInterface ifc, PetscInt k)
{
  const PetscInt       i = ifc->kcouple[k];
  const MBCCoupleDesc *d = JointDesc(ifc, i);
  if (MBCInterfaceJointPoint(ifc, i, ifc->kpoint[k], NULL) != 1) return 0;
  if (ifc->jsoft && ifc->jsoft[i]) { /* softening: the cone of (1 - D) c with mu(D) */
    const PetscReal D = MBCInterfaceJointDamage(ifc, i, ifc->kpoint[k]);
    return ifc->dscale * (1 - D) * d->cohesion / MBCInterfaceJointMu(ifc, k) * ifc->contact->couples[i].points[ifc->kpoint[k]].area / ifc->theta;
  }
  return ifc->dscale * d->cohesion / d->mu * ifc->contact->couples[i].points[ifc->kpoint[k]].area / ifc->theta;
}

/* This rank's rows: the shift s (r's layout, the normal rows of bonded points) and each point's
   mu in the problem. */
PetscErrorCode MBCInterfaceJointProblem(MBCInterface ifc, Vec s)
{
  PetscScalar *a;
  PetscInt     rstart;

  PetscFunctionBegin;
  PetscCall(JointSetUp(ifc));
  PetscCall(VecGetOwnershipRange(s, &rstart, NULL));
  PetscCall(VecGetArray(s, &a));
  for (PetscInt p = ifc->pfirst; p < ifc->plast; p++) {
    const PetscInt k = ifc->order[p];
    for (PetscInt d = ifc->poff[p]; d < ifc->poff[p + 1]; d++) a[d - rstart] = 0;
    a[ifc->poff[p] - rstart]   = JointShift(ifc, k);
    ifc->fp.mu[p - ifc->pfirst] = MBCInterfaceJointMu(ifc, k);
  }
  PetscCall(VecRestoreArray(s, &a));
  PetscFunctionReturn(0);
}

/* How far point k's traction lies beyond its bonded cone, in units of its apex force (c/mu) A:
   the larger of the tension beyond the cut-off, -z_n - f_t A, and of the shear beyond the slip
   line, |z_t| - (c A + mu z_n) over mu (z: the mean force, from r; > 0 outside, <= 0 inside). */
static PetscReal JointExceedance(MBCInterface ifc, PetscInt k)
{
  const PetscInt       i = ifc->kcouple[k], o = ifc->coff[k];
  const MBCCoupleDesc *d = JointDesc(ifc, i);
  const PetscReal      A = ifc->contact->couples[i].points[ifc->kpoint[k]].area, f = ifc->theta / ifc->dscale, F = d->cohesion / d->mu * A;
  const PetscReal      zn = f * ifc->rall[o], zt = f * PetscSqrtReal(PetscSqr(ifc->rall[o + 1]) + PetscSqr(ifc->rall[o + 2]));
  if (ifc->jsoft && ifc->jsoft[i]) { /* softening: the cone's boundary softens the bond (MBCInterfaceJointSoften); only a cut-off below the apex breaks */
    const PetscReal D = MBCInterfaceJointDamage(ifc, i, ifc->kpoint[k]);
    if (!(d->tensile < d->cohesion / d->mu * (1 - 1e-12))) return -1;
    return (-zn - (1 - D) * d->tensile * A) / F;
  }
  return PetscMax(-zn - d->tensile * A, (zt - d->cohesion * A - d->mu * zn) / d->mu) / F;
}

/* After a solve (rall: r of every point, couple order, the same on every rank): bonded points whose
   traction reached the cone's boundary (the cut-off p = -f_t or the slip line |t| = c + mu p,
   within jtol of the apex force) break at `time`; *nnew of them. -mbc_joint_break_fraction (jfrac)
   < 1 breaks only the points within that fraction of the largest excess before the next solve
   (the most loaded first: a break moves load onto the neighbours and may relieve points further
   on); points tied with the worst always break together, so a uniform joint breaks in one solve.
   The default, 1, breaks every point beyond: on the cracked base of test_joint_law.py the crack
   lengths agree with 0.5 and 0 to the cell size and it takes the fewest solves (29 for the whole
   crack, against 37 and 42). Points with no area carry nothing and are not judged. */
PetscErrorCode MBCInterfaceJointBreak(MBCInterface ifc, PetscReal time, PetscInt *nnew)
{
  PetscReal worst = -PETSC_MAX_REAL, bar;

  PetscFunctionBegin;
  *nnew = 0;
  PetscCall(JointSetUp(ifc));
  for (PetscInt k = 0; k < ifc->ncontact; k++) {
    const PetscInt i = ifc->kcouple[k], j = ifc->kpoint[k];
    if (MBCInterfaceJointPoint(ifc, i, j, NULL) != 1 || !(ifc->contact->couples[i].points[j].area > 0)) continue;
    worst = PetscMax(worst, JointExceedance(ifc, k));
  }
  if (!(worst >= -ifc->jtol)) PetscFunctionReturn(0);
  bar = PetscMax(-ifc->jtol, (1 - ifc->jfrac) * worst - ifc->jtol);
  for (PetscInt k = 0; k < ifc->ncontact; k++) {
    const PetscInt i = ifc->kcouple[k], j = ifc->kpoint[k];
    if (MBCInterfaceJointPoint(ifc, i, j, NULL) != 1 || !(ifc->contact->couples[i].points[j].area > 0)) continue;
    if (JointExceedance(ifc, k) >= bar) {
      ifc->jbreak[i][ifc->contact->couples[i].points[j].master] = time;
      (*nnew)++;
    }
  }
  PetscFunctionReturn(0);
}

/* Softening couples, after a solve (rall, uall of every point): each bonded point's damage from its
   relative displacement, D = max(D_base, min(1, (S_base + |u_t| + max(u_n, 0)) / delta_s)): the slip
   summed where the step began plus this step's slip (u_t: from the step's start, static: the load
   step's) and the opening (u_n: the gap after the step); a point that reaches D = 1 breaks at `time`.
   *nnew: the breaks, *dmax: the largest change of D (the caller solves again until it is small:
   a fixed point in D, increasing since more damage means more slip, so it converges, to D = 1
   where the bond has no state short of breaking). */
PetscErrorCode MBCInterfaceJointSoften(MBCInterface ifc, PetscReal time, PetscInt *nnew, PetscReal *dmax)
{
  PetscFunctionBegin;
  *nnew = 0, *dmax = 0;
  PetscCall(JointSetUp(ifc));
  for (PetscInt k = 0; k < ifc->ncontact; k++) {
    const PetscInt i = ifc->kcouple[k], j = ifc->kpoint[k], o = ifc->coff[k];
    PetscReal     *st, ut, D;
    if (!ifc->jsoft[i] || MBCInterfaceJointPoint(ifc, i, j, NULL) != 1 || !(ifc->contact->couples[i].points[j].area > 0)) continue;
    st    = &ifc->jsoft[i][4 * ifc->contact->couples[i].points[j].master];
    ut    = PetscSqrtReal(PetscSqr(ifc->uall[o + 1]) + PetscSqr(ifc->uall[o + 2]));
    D     = PetscMax(st[1], PetscMin(1, (st[2] + ut + PetscMax(ifc->uall[o], 0)) / JointDesc(ifc, i)->softening));
    *dmax = PetscMax(*dmax, PetscAbsReal(D - st[0]));
    st[0] = D, st[3] = ut;
    if (D >= 1 - 1e-12) {
      ifc->jbreak[i][ifc->contact->couples[i].points[j].master] = time;
      (*nnew)++;
    }
  }
  PetscFunctionReturn(0);
}

/* Softening couples: the step's damage and slip become the base of the next step (a dynamic step
   that succeeded, or a static load step that begins: commit), or the step is abandoned (its damage
   undone). */
PetscErrorCode MBCInterfaceJointCommit(MBCInterface ifc, PetscBool commit)
{
  PetscFunctionBegin;
  for (PetscInt i = 0; ifc->jsoft && i < ifc->contact->ncouples; i++)
    for (PetscInt m = 0; ifc->jsoft[i] && m < ifc->contact->couples[i].master.nnodes; m++) {
      PetscReal *st = &ifc->jsoft[i][4 * m];
      if (commit) st[1] = st[0], st[2] += st[3];
      else st[0] = st[1];
      st[3] = 0;
    }
  PetscFunctionReturn(0);
}

/* The break state where a load step begins (saved) and where it is abandoned (restored). */
PetscErrorCode MBCInterfaceJointSave(MBCInterface ifc, PetscBool restore)
{
  PetscFunctionBegin;
  if (!ifc->jbreak) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < ifc->contact->ncouples; i++) {
    if (!ifc->jbreak[i]) continue;
    if (restore) PetscCall(PetscArraycpy(ifc->jbreak[i], ifc->jsave[i], ifc->contact->couples[i].master.nnodes));
    else PetscCall(PetscArraycpy(ifc->jsave[i], ifc->jbreak[i], ifc->contact->couples[i].master.nnodes));
  }
  PetscFunctionReturn(0);
}

/* A failed solve at `time` (the step is cut): the bonds that broke at that time are whole again. */
PetscErrorCode MBCInterfaceJointUnbreak(MBCInterface ifc, PetscReal time)
{
  PetscFunctionBegin;
  for (PetscInt i = 0; ifc->jbreak && i < ifc->contact->ncouples; i++)
    for (PetscInt m = 0; ifc->jbreak[i] && m < ifc->contact->couples[i].master.nnodes; m++)
      if (ifc->jbreak[i][m] == time) ifc->jbreak[i][m] = PETSC_MAX_REAL;
  PetscFunctionReturn(0);
}

/* For the checkpoint: every bonded couple's break times, couple after couple, per master node
   (n of them; NULL t: the count only); and back. */
PetscErrorCode MBCInterfaceJointGetState(MBCInterface ifc, PetscInt *n, PetscReal t[])
{
  PetscFunctionBegin;
  *n = 0;
  if (!MBCInterfaceHasJoints(ifc)) PetscFunctionReturn(0);
  PetscCall(JointSetUp(ifc));
  for (PetscInt i = 0; i < ifc->contact->ncouples; i++) {
    if (!ifc->jbreak[i]) continue;
    if (t) PetscCall(PetscArraycpy(t + *n, ifc->jbreak[i], ifc->contact->couples[i].master.nnodes));
    *n += ifc->contact->couples[i].master.nnodes;
  }
  for (PetscInt i = 0; i < ifc->contact->ncouples; i++) { /* softening: D and the slip summed, the step's included */
    if (!ifc->jsoft[i]) continue;
    for (PetscInt m = 0; t && m < ifc->contact->couples[i].master.nnodes; m++) t[*n + 2 * m] = ifc->jsoft[i][4 * m], t[*n + 2 * m + 1] = ifc->jsoft[i][4 * m + 2] + ifc->jsoft[i][4 * m + 3];
    *n += 2 * ifc->contact->couples[i].master.nnodes;
  }
  PetscFunctionReturn(0);
}

PetscErrorCode MBCInterfaceJointSetState(MBCInterface ifc, PetscInt n, const PetscReal t[])
{
  PetscInt m;

  PetscFunctionBegin;
  PetscCall(MBCInterfaceJointGetState(ifc, &m, NULL));
  PetscCheck(m == n, ifc->comm, PETSC_ERR_FILE_UNEXPECTED, "Checkpoint: %" PetscInt_FMT " joint values (break times, and damage and slip where softening) where the scene's bonded couples need %" PetscInt_FMT, n, m);
  m = 0;
  for (PetscInt i = 0; i < ifc->contact->ncouples; i++) {
    if (!ifc->jbreak[i]) continue;
    PetscCall(PetscArraycpy(ifc->jbreak[i], t + m, ifc->contact->couples[i].master.nnodes));
    PetscCall(PetscArraycpy(ifc->jsave[i], t + m, ifc->contact->couples[i].master.nnodes));
    m += ifc->contact->couples[i].master.nnodes;
  }
  for (PetscInt i = 0; i < ifc->contact->ncouples; i++) {
    if (!ifc->jsoft[i]) continue;
    for (PetscInt l = 0; l < ifc->contact->couples[i].master.nnodes; l++) {
      PetscReal *st = &ifc->jsoft[i][4 * l];
      st[0] = st[1] = t[m + 2 * l], st[2] = t[m + 2 * l + 1], st[3] = 0;
    }
    m += 2 * ifc->contact->couples[i].master.nnodes;
  }
  PetscFunctionReturn(0);
}
