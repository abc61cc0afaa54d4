/* Pressure and traction on a surface, integrated by hand on each face (tri3, quad4, and the tri6
   faces of tet10 bodies): f_i = int N_i t dA with t = -p n (pressure, against the outward normal)
   or the given traction. tri3 by its 3-point rule (degree 2), quad4 by 2 x 2 Gauss points (the
   rule PetscFE's order-2 quadrature used on them), tri6 by a collapsed 3 x 3 Gauss rule (degree 5:
   exact for a curved face's N_i times its quadratic area element). A tri6 face's consistent forces
   from a uniform pressure are 0 at its corners and a third of its area at its midside nodes. */
#include <mbc/private/bodyimpl.h>
#include <petscbt.h>
#include <petscsf.h>

/* Shape functions and their derivatives on the face of nv nodes at (a, b): tri3 and tri6 in
   (xi, eta) of the triangle (0,0) (1,0) (0,1) (corners, then the midside nodes of (c0 c1) (c1 c2)
   (c2 c0)), quad4 in [-1, 1]^2 (corners cyclic). */
void MBCFaceShape(PetscInt nv, PetscReal a, PetscReal b, PetscReal N[6], PetscReal dN[6][2])
{
  if (nv == 4) {
    static const PetscReal su[4] = {-1, 1, 1, -1}, sv[4] = {-1, -1, 1, 1};
    for (PetscInt i = 0; i < 4; i++) {
      N[i]     = 0.25 * (1 + su[i] * a) * (1 + sv[i] * b);
      dN[i][0] = 0.25 * su[i] * (1 + sv[i] * b);
      dN[i][1] = 0.25 * sv[i] * (1 + su[i] * a);
    }
    return;
  }
  {
    const PetscReal L[3] = {1 - a - b, a, b}, dL[3][2] = {{-1, -1}, {1, 0}, {0, 1}};
    if (nv == 3) {
      for (PetscInt i = 0; i < 3; i++) N[i] = L[i], dN[i][0] = dL[i][0], dN[i][1] = dL[i][1];
      return;
    }
    for (PetscInt i = 0; i < 3; i++) {
      const PetscInt j = (i + 1) % 3;
      N[i]             = L[i] * (2 * L[i] - 1);
      N[3 + i]         = 4 * L[i] * L[j];
      for (PetscInt k = 0; k < 2; k++) {
        dN[i][k]     = (4 * L[i] - 1) * dL[i][k];
        dN[3 + i][k] = 4 * (dL[i][k] * L[j] + L[i] * dL[j][k]);
      }
    }
  }
}

/* Quadrature point q of the face's rule: (a, b) and weight; returns the number of points. */
PetscInt MBCFaceQuadrature(PetscInt nv, PetscInt q, PetscReal *a, PetscReal *b, PetscReal *w)
{
  if (nv == 3) {
    static const PetscReal p[3][2] = {
      {1.0 / 6, 1.0 / 6},
      {2.0 / 3, 1.0 / 6},
      {1.0 / 6, 2.0 / 3}
    };
    *a = p[q][0], *b = p[q][1], *w = 1.0 / 6;
    return 3;
  }
  if (nv == 4) {
    const PetscReal g = 1.0 / PetscSqrtReal(3.0);
    *a = q % 2 ? g : -g, *b = q / 2 ? g : -g, *w = 1;
    return 4;
  }
  {
    static const PetscReal x[3] = {0.1127016653792583, 0.5, 0.8872983346207417}, gw[3] = {5.0 / 18, 8.0 / 18, 5.0 / 18};
    const PetscReal        u = x[q / 3], v = x[q % 3];
    *a = u, *b = v * (1 - u), *w = gw[q / 3] * gw[q % 3] * (1 - u);
    return 9;
  }
}

/* The face of nv nodes X at (a, b): its shape functions N, the point x and the tangents xa, xb */
void MBCFaceMap(PetscInt nv, const PetscReal X[6][3], PetscReal a, PetscReal b, PetscReal N[6], PetscReal x[3], PetscReal xa[3], PetscReal xb[3])
{
  PetscReal dN[6][2];

  MBCFaceShape(nv, a, b, N, dN);
  for (PetscInt c = 0; c < 3; c++) x[c] = xa[c] = xb[c] = 0;
  for (PetscInt i = 0; i < nv; i++)
    for (PetscInt c = 0; c < 3; c++) {
      xa[c] += dN[i][0] * X[i][c];
      xb[c] += dN[i][1] * X[i][c];
      x[c] += N[i] * X[i][c];
    }
}

/* Adds the nodal forces of the surface load on one face (nodes X, outward winding) to f:
   pressure(x) against the normal when pressure is given, else the constant traction t. */
void MBCFaceIntegrate(PetscInt nv, const PetscReal X[6][3], PetscReal (*pressure)(const PetscReal[3], void *), void *ctx, const PetscReal t[3], PetscReal f[6][3])
{
  const PetscInt nq = MBCFaceQuadrature(nv, 0, &(PetscReal){0}, &(PetscReal){0}, &(PetscReal){0});
  for (PetscInt q = 0; q < nq; q++) {
    PetscReal a, b, w, N[6], xa[3], xb[3], x[3], nA[3], dA;
    (void)MBCFaceQuadrature(nv, q, &a, &b, &w);
    MBCFaceMap(nv, X, a, b, N, x, xa, xb);
    nA[0] = xa[1] * xb[2] - xa[2] * xb[1];
    nA[1] = xa[2] * xb[0] - xa[0] * xb[2];
    nA[2] = xa[0] * xb[1] - xa[1] * xb[0];
    dA    = PetscSqrtReal(nA[0] * nA[0] + nA[1] * nA[1] + nA[2] * nA[2]);
    if (pressure) {
      const PetscReal p = pressure(x, ctx);
      for (PetscInt i = 0; i < nv; i++)
        for (PetscInt c = 0; c < 3; c++) f[i][c] -= w * p * N[i] * nA[c];
    } else
      for (PetscInt i = 0; i < nv; i++)
        for (PetscInt c = 0; c < 3; c++) f[i][c] += w * t[c] * N[i] * dA;
  }
}

static PetscReal ConstantPressure(const PetscReal x[3], void *ctx)
{
  (void)x;
  return *(PetscReal *)ctx;
}

/* F = the nodal forces of the faces of surface `id` that this rank owns (each face once over the
   ranks), face() giving each face's: its nodes pts[0 .. *n) and their forces f (zeroed; *n = 0:
   none), from the local coordinates x. The loop of every face load (pressure and traction,
   hydrostatic, uplift); collective on the body. */
PetscErrorCode MBCBodyAssembleFaces(MBCBody body, PetscInt id, MBCFaceForceFn face, void *ctx, Vec F)
{
  DM                 dm = body->dm;
  DMLabel            label;
  PetscSection       lsec;
  Vec                coords, Floc;
  const PetscScalar *x;
  PetscScalar       *fl;
  PetscSF            sf;
  PetscBT            notmine;
  IS                 faceIS = NULL;
  const PetscInt    *faces  = NULL, *leaves;
  PetscInt           nfaces = 0, pStart, pEnd, nleaves;

  PetscFunctionBegin;
  PetscCall(VecZeroEntries(F));
  PetscCall(DMGetLabel(dm, "Face Sets", &label));
  if (label) PetscCall(DMLabelGetStratumIS(label, id, &faceIS));
  /* no early return for a rank without faces: the coordinates and DMLocalToGlobal() are collective */
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
    PetscInt  pts[6], n = 0;
    PetscReal f[6][3];
    if (PetscBTLookup(notmine, faces[fi])) continue;
    PetscCall(PetscArrayzero(&f[0][0], 18));
    PetscCall(face(body, faces[fi], x, ctx, pts, f, &n));
    for (PetscInt v = 0; v < n; v++) {
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

/* a pressure's or traction's forces on one face */
static PetscErrorCode FaceLoadForces(MBCBody body, PetscInt face, const PetscScalar x[], void *ctx, PetscInt pts[6], PetscReal f[6][3], PetscInt *n)
{
  const MBCLoadDesc *load = (const MBCLoadDesc *)ctx;
  PetscReal          X[6][3], p = load->value;
  PetscInt           nc;

  PetscFunctionBegin;
  PetscCall(MBCBodyFaceNodes(body, face, x, pts, X, n, &nc));
  if (load->kind == MBC_LOAD_PRESSURE) MBCFaceIntegrate(*n, (const PetscReal(*)[3])X, ConstantPressure, &p, NULL, f);
  else MBCFaceIntegrate(*n, (const PetscReal(*)[3])X, NULL, NULL, load->vector, f);
  PetscFunctionReturn(0);
}

/* F: the nodal forces of a pressure or traction load for a unit time factor. */
PetscErrorCode MBCBodyAssembleFaceLoad(MBCBody body, MBCLoadDesc *load, Vec F)
{
  PetscFunctionBegin;
  PetscCall(MBCBodyAssembleFaces(body, load->surface_id, FaceLoadForces, load, F));
  PetscFunctionReturn(0);
}
