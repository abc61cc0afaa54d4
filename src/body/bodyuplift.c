/* Uplift on a couple's faces (docs/scene.md, couples' `uplift`; docs/dam.md, Uplift): the water
   pressure in a joint, on both of its faces, as consistent nodal loads on the bodies' right-hand
   sides. Along s = (x - origin) . direction, 0 <= s <= L (0 outside: the joint ends there):

   - the heel-to-toe law (USACE EM 1110-2-2200, FERC chapter III, CADAM): heads H1 at the heel,
     H2 (tail water) at the toe, linear between; with a drain line at s = X of efficiency E the
     head there is H3 = H2 + (1 - E)(H1 - H2)(L - X)/(L - s0), linear H1 -> H3 -> H2;
   - or a table p(s), linear between its rows and constant beyond its ends;
   - with penetration, the wet length w (solveruplift.c: the joint open from the heel up to its
     first closed point) carries the reservoir's pressure at its depth, unit_weight (level - x_axis),
     and the law starts at s0 = w with H1 (the crack's tip takes the heel's head; past the drains
     they no longer act: H1 -> H2 linear), as the cracked-base analysis of USACE and FERC.

   The field is piecewise linear in s: a face whose s-range holds no kink is integrated by a
   3 x 3 Gauss rule (exact on flat faces), one a kink crosses on a 12 x 12 grid of such rules. */
#include <mbc/private/bodyimpl.h>
#include <petscbt.h>
#include <petscsf.h>

#define UPLIFT_SUB 12

/* The law's head along s from s0 (the heel, or the wet length's end). */
static PetscReal UpliftLawHead(const MBCUpliftDesc *u, PetscReal s0, PetscReal s)
{
  const PetscReal H1 = u->heel_head, H2 = u->tail_head, L = u->length;

  if (s <= s0) return H1;
  if (s0 >= L) return H1;
  if (u->drain > s0 && u->drain < L) {
    const PetscReal X = u->drain, H3 = H2 + (1 - u->efficiency) * (H1 - H2) * (L - X) / (L - s0);
    if (s <= X) return H1 + (H3 - H1) * (s - s0) / (X - s0);
    return H3 + (H2 - H3) * (s - X) / (L - X);
  }
  return H1 + (H2 - H1) * (s - s0) / (L - s0);
}

/* The uplift pressure at x, the wet length w from the heel. */
PetscReal MBCUpliftPressure(const MBCUpliftDesc *u, PetscReal w, const PetscReal x[3])
{
  const PetscReal s = (x[0] - u->origin[0]) * u->direction[0] + (x[1] - u->origin[1]) * u->direction[1] + (x[2] - u->origin[2]) * u->direction[2];

  if (s < 0 || s > u->length) return 0;
  if (u->penetration && s < w) return u->unit_weight * PetscMax(u->level - x[u->axis], 0);
  if (u->ntable > 0) {
    const PetscReal *T = u->table;
    const PetscInt   n = u->ntable;
    if (s <= T[0]) return T[1];
    if (s >= T[2 * (n - 1)]) return T[2 * n - 1];
    for (PetscInt r = 1; r < n; r++)
      if (s <= T[2 * r]) return T[2 * r - 1] + (T[2 * r + 1] - T[2 * r - 1]) * (s - T[2 * r - 2]) / (T[2 * r] - T[2 * r - 2]);
  }
  return u->unit_weight * PetscMax(UpliftLawHead(u, u->penetration ? PetscMin(w, u->length) : 0, s), 0);
}

/* Whether the field has a kink strictly inside (a, b): the joint's ends, the wet length, the drain,
   the table's rows. */
static PetscBool UpliftKinkIn(const MBCUpliftDesc *u, PetscReal w, PetscReal a, PetscReal b)
{
  const PetscReal tol = 1e-12 * (u->length + PetscAbsReal(a) + PetscAbsReal(b));
  PetscReal       k[4] = {0, u->length, u->penetration ? w : -1, u->drain};
  for (PetscInt i = 0; i < 4; i++)
    if (k[i] > a + tol && k[i] < b - tol) return PETSC_TRUE;
  for (PetscInt r = 0; r < u->ntable; r++)
    if (u->table[2 * r] > a + tol && u->table[2 * r] < b - tol) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* Adds the nodal forces of the uplift on one face (nodes X, outward winding) to f, and the face's
   share of int p dA and int p x dA to r[4]: sub x sub cells of the reference face, 3 x 3 Gauss
   points each (a triangle through the collapsed square). */
static void UpliftFace(const MBCUpliftDesc *u, PetscReal w, PetscInt nv, const PetscReal X[6][3], PetscInt sub, PetscReal f[6][3], PetscReal r[4])
{
  static const PetscReal gx[3] = {0.1127016653792583, 0.5, 0.8872983346207417}, gw[3] = {5.0 / 18, 8.0 / 18, 5.0 / 18};

  for (PetscInt ci = 0; ci < sub; ci++)
    for (PetscInt cj = 0; cj < sub; cj++)
      for (PetscInt qi = 0; qi < 3; qi++)
        for (PetscInt qj = 0; qj < 3; qj++) {
          const PetscReal U = (ci + gx[qi]) / sub, V = (cj + gx[qj]) / sub, W = gw[qi] * gw[qj] / (sub * sub);
          PetscReal       a, b, jac, N[6], dN[6][2], xa[3] = {0, 0, 0}, xb[3] = {0, 0, 0}, x[3] = {0, 0, 0}, nA[3], p;
          if (nv == 4) a = 2 * U - 1, b = 2 * V - 1, jac = 4; /* [0, 1]^2 -> [-1, 1]^2 */
          else a = U, b = V * (1 - U), jac = 1 - U;           /* the collapsed square */
          MBCFaceShape(nv, a, b, N, dN);
          for (PetscInt i = 0; i < nv; i++)
            for (PetscInt c = 0; c < 3; c++) {
              xa[c] += dN[i][0] * X[i][c];
              xb[c] += dN[i][1] * X[i][c];
              x[c] += N[i] * X[i][c];
            }
          p = MBCUpliftPressure(u, w, x);
          if (p == 0) continue;
          nA[0] = xa[1] * xb[2] - xa[2] * xb[1];
          nA[1] = xa[2] * xb[0] - xa[0] * xb[2];
          nA[2] = xa[0] * xb[1] - xa[1] * xb[0];
          {
            const PetscReal wq = W * jac, dA = PetscSqrtReal(nA[0] * nA[0] + nA[1] * nA[1] + nA[2] * nA[2]);
            for (PetscInt i = 0; i < nv; i++)
              for (PetscInt c = 0; c < 3; c++) f[i][c] -= wq * p * N[i] * nA[c];
            r[0] += wq * p * dA;
            for (PetscInt c = 0; c < 3; c++) r[1 + c] += wq * p * dA * x[c];
          }
        }
}

/* F: the nodal forces of an uplift load for a unit time factor at wet length w; r[4] (this rank's
   owned faces): int p dA and int p x dA over the load's faces. */
PetscErrorCode MBCBodyAssembleUplift(MBCBody body, MBCLoadDesc *load, PetscReal w, Vec F, PetscReal r[4])
{
  const MBCUpliftDesc *u  = &body->scene->couples[load->couple].uplift;
  DM                   dm = body->dm;
  DMLabel              label;
  PetscSection         lsec;
  Vec                  coords, Floc;
  const PetscScalar   *x;
  PetscScalar         *fl;
  PetscSF              sf;
  PetscBT              notmine;
  IS                   faceIS = NULL;
  const PetscInt      *faces  = NULL, *leaves;
  PetscInt             nfaces = 0, pStart, pEnd, nleaves;

  PetscFunctionBegin;
  PetscCall(PetscArrayzero(r, 4));
  PetscCall(VecZeroEntries(F));
  PetscCall(DMGetLabel(dm, "Face Sets", &label));
  if (label) PetscCall(DMLabelGetStratumIS(label, load->surface_id, &faceIS));
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(PetscBTCreate(pEnd, &notmine)); /* points this rank does not own: leaves of the point SF */
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFGetGraph(sf, NULL, &nleaves, &leaves, NULL));
  for (PetscInt i = 0; i < nleaves && nleaves > 0; i++) PetscCall(PetscBTSet(notmine, leaves ? leaves[i] : i));
  PetscCall(DMGetLocalVector(dm, &Floc));
  PetscCall(VecZeroEntries(Floc));
  PetscCall(VecGetArray(Floc, &fl));
  PetscCall(VecGetArrayRead(coords, &x));
  if (faceIS) PetscCall(ISGetLocalSize(faceIS, &nfaces));
  if (faceIS) PetscCall(ISGetIndices(faceIS, &faces));
  for (PetscInt fi = 0; fi < nfaces; fi++) {
    PetscInt  pts[6], nv, nc;
    PetscReal X[6][3], f[6][3], smin = PETSC_MAX_REAL, smax = PETSC_MIN_REAL;
    if (PetscBTLookup(notmine, faces[fi])) continue;
    PetscCall(MBCBodyFaceNodes(body, faces[fi], x, pts, X, &nv, &nc));
    for (PetscInt v = 0; v < nv; v++) {
      const PetscReal s = (X[v][0] - u->origin[0]) * u->direction[0] + (X[v][1] - u->origin[1]) * u->direction[1] + (X[v][2] - u->origin[2]) * u->direction[2];
      smin = PetscMin(smin, s), smax = PetscMax(smax, s);
    }
    if (smax < 0 || smin > u->length) continue;
    PetscCall(PetscArrayzero(&f[0][0], 18));
    UpliftFace(u, w, nv, (const PetscReal(*)[3])X, UpliftKinkIn(u, w, smin, smax) ? UPLIFT_SUB : 1, f, r);
    for (PetscInt v = 0; v < nv; v++) {
      PetscInt off;
      PetscCall(PetscSectionGetOffset(lsec, pts[v], &off));
      for (PetscInt c = 0; c < 3; c++) fl[off + c] += f[v][c];
    }
  }
  if (faceIS) PetscCall(ISRestoreIndices(faceIS, &faces));
  PetscCall(ISDestroy(&faceIS));
  PetscCall(VecRestoreArrayRead(coords, &x));
  PetscCall(VecRestoreArray(Floc, &fl));
  PetscCall(PetscBTDestroy(&notmine));
  PetscCall(DMLocalToGlobal(dm, Floc, ADD_VALUES, F));
  PetscCall(DMRestoreLocalVector(dm, &Floc));
  PetscFunctionReturn(0);
}

/* The body's uplift loads again for the wet lengths w[] (per couple of the scene); r[4 * couple]
   gets this rank's int p dA and int p x dA over the master faces of each couple (for a unit time
   factor). A rigid body's faces load it as a pressure does. */
PetscErrorCode MBCBodyUpliftUpdate(MBCBody body, const PetscReal w[], PetscReal r[])
{
  MBCScene scene = body->scene;

  PetscFunctionBegin;
  for (PetscInt i = 0; i < body->nloads; i++) {
    MBCLoadDesc *load = &scene->loads[body->load_index[i]];
    PetscReal    rl[4];
    if (load->kind != MBC_LOAD_UPLIFT) continue;
    PetscCall(MBCBodyAssembleUplift(body, load, w[load->couple], body->load[i], rl));
    if (load->side == 0) /* the couple's resultant is its master side's */
      for (PetscInt k = 0; k < 4; k++) r[4 * load->couple + k] += rl[k];
  }
  PetscFunctionReturn(0);
}
