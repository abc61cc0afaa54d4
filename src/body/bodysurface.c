/* Lumped nodal 3 x 3 blocks on a surface of a body: the reservoir's added mass (bodyaddedmass.c)
   and the absorbing boundaries' dashpots (bodyabsorbing.c). Each face of the surface gives its
   vertices the weights w_i of a caller's rule (an integral of N_i times a density over the face)
   and every vertex gets w_i (a n n^T + b (I - n n^T)), n the face's unit outward normal: a curved
   surface's nodes sum the blocks of the faces around them, each along its own normal (Kuo's
   generalised Westergaard). */
#include <mbc/private/bodyimpl.h>
#include <petscbt.h>
#include <petscsf.h>

/* Adds the blocks of the faces of surface `id` this rank owns to A (MatSetValuesLocal, the DM's
   local numbering); the caller assembles A. */
PetscErrorCode MBCBodySurfaceBlocks(MBCBody body, PetscInt id, MBCFaceWeights weights, void *ctx, PetscReal a, PetscReal b, Mat A)
{
  DM                 dm = body->dm;
  DMLabel            label;
  PetscSection       csec, lsec;
  Vec                coords;
  const PetscScalar *x;
  PetscSF            sf;
  PetscBT            notmine;
  IS                 faceIS = NULL;
  const PetscInt    *faces  = NULL, *leaves;
  PetscInt           nfaces = 0, vStart, vEnd, pStart, pEnd, nleaves;

  PetscFunctionBegin;
  PetscCall(DMGetLabel(dm, "Face Sets", &label));
  if (label) PetscCall(DMLabelGetStratumIS(label, id, &faceIS));
  if (!faceIS) PetscFunctionReturn(0);
  PetscCall(DMGetCoordinateSection(dm, &csec));
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
  PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
  PetscCall(DMPlexGetChart(dm, &pStart, &pEnd));
  PetscCall(PetscBTCreate(pEnd, &notmine));
  PetscCall(DMGetPointSF(dm, &sf));
  PetscCall(PetscSFGetGraph(sf, NULL, &nleaves, &leaves, NULL));
  for (PetscInt i = 0; i < nleaves && nleaves > 0; i++) PetscCall(PetscBTSet(notmine, leaves ? leaves[i] : i));
  PetscCall(VecGetArrayRead(coords, &x));
  PetscCall(ISGetLocalSize(faceIS, &nfaces));
  PetscCall(ISGetIndices(faceIS, &faces));
  for (PetscInt fi = 0; fi < nfaces; fi++) {
    const PetscInt  face = faces[fi];
    PetscInt       *closure = NULL, nclosure, nv = 0, vert[4], ns, ncv = 0;
    const PetscInt *support;
    PetscReal       X[4][3], fc[3] = {0, 0, 0}, cc[3] = {0, 0, 0}, n[3] = {0, 0, 0}, w[4] = {0, 0, 0, 0}, len;

    if (PetscBTLookup(notmine, face)) continue;
    PetscCall(DMPlexGetTransitiveClosure(dm, face, PETSC_TRUE, &nclosure, &closure)); /* vertices in cyclic order */
    for (PetscInt p = 0; p < 2 * nclosure; p += 2)
      if (closure[p] >= vStart && closure[p] < vEnd && nv < 4) vert[nv++] = closure[p];
    PetscCall(DMPlexRestoreTransitiveClosure(dm, face, PETSC_TRUE, &nclosure, &closure));
    PetscCheck(nv == 3 || nv == 4, PETSC_COMM_SELF, PETSC_ERR_SUP, "Body '%s': surface %" PetscInt_FMT ": a face with %" PetscInt_FMT " vertices", body->name, id, nv);
    for (PetscInt v = 0; v < nv; v++) {
      PetscInt coff;
      PetscCall(PetscSectionGetOffset(csec, vert[v], &coff));
      for (PetscInt c = 0; c < 3; c++) {
        X[v][c] = PetscRealPart(x[coff + c]);
        fc[c] += X[v][c] / nv;
      }
    }
    for (PetscInt v = 0; v < nv; v++) { /* Newell's normal */
      const PetscReal *p = X[v], *q = X[(v + 1) % nv];
      n[0] += (p[1] - q[1]) * (p[2] + q[2]);
      n[1] += (p[2] - q[2]) * (p[0] + q[0]);
      n[2] += (p[0] - q[0]) * (p[1] + q[1]);
    }
    PetscCall(DMPlexGetSupportSize(dm, face, &ns));
    PetscCall(DMPlexGetSupport(dm, face, &support));
    PetscCheck(ns == 1, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG, "Body '%s': surface %" PetscInt_FMT ": a face is not on the body's boundary", body->name, id);
    PetscCall(DMPlexGetTransitiveClosure(dm, support[0], PETSC_TRUE, &nclosure, &closure));
    for (PetscInt p = 0; p < 2 * nclosure; p += 2) {
      PetscInt coff;
      if (closure[p] < vStart || closure[p] >= vEnd) continue;
      PetscCall(PetscSectionGetOffset(csec, closure[p], &coff));
      for (PetscInt c = 0; c < 3; c++) cc[c] += PetscRealPart(x[coff + c]);
      ncv++;
    }
    PetscCall(DMPlexRestoreTransitiveClosure(dm, support[0], PETSC_TRUE, &nclosure, &closure));
    if (n[0] * (fc[0] - cc[0] / ncv) + n[1] * (fc[1] - cc[1] / ncv) + n[2] * (fc[2] - cc[2] / ncv) < 0) { /* outward winding */
      for (PetscInt i = 1, j = nv - 1; i < j; i++, j--) {
        PetscInt tv = vert[i];
        vert[i] = vert[j], vert[j] = tv;
        for (PetscInt c = 0; c < 3; c++) {
          PetscReal t = X[i][c];
          X[i][c] = X[j][c], X[j][c] = t;
        }
      }
      for (PetscInt c = 0; c < 3; c++) n[c] = -n[c];
    }
    len = PetscSqrtReal(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(len > 0)) continue; /* a degenerate face has no area */
    for (PetscInt c = 0; c < 3; c++) n[c] /= len;
    PetscCall(weights(nv, (const PetscReal(*)[3])X, ctx, w));
    for (PetscInt v = 0; v < nv; v++) {
      PetscInt    off, idx[3];
      PetscScalar blk[9];
      if (w[v] == 0) continue;
      PetscCall(PetscSectionGetOffset(lsec, vert[v], &off));
      for (PetscInt i = 0; i < 3; i++) {
        idx[i] = off + i;
        for (PetscInt j = 0; j < 3; j++) blk[3 * i + j] = w[v] * ((a - b) * n[i] * n[j] + (i == j ? b : 0.0));
      }
      PetscCall(MatSetValuesLocal(A, 3, idx, 3, idx, blk, ADD_VALUES));
    }
  }
  PetscCall(ISRestoreIndices(faceIS, &faces));
  PetscCall(ISDestroy(&faceIS));
  PetscCall(VecRestoreArrayRead(coords, &x));
  PetscCall(PetscBTDestroy(&notmine));
  PetscFunctionReturn(0);
}
