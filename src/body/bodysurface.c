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
  PetscSection       lsec;
  Vec                coords;
  const PetscScalar *x;
  PetscSF            sf;
  PetscBT            notmine;
  IS                 faceIS = NULL;
  const PetscInt    *faces  = NULL, *leaves;
  PetscInt           nfaces = 0, pStart, pEnd, nleaves;

  PetscFunctionBegin;
  PetscCall(DMGetLabel(dm, "Face Sets", &label));
  if (label) PetscCall(DMLabelGetStratumIS(label, id, &faceIS));
  if (!faceIS) PetscFunctionReturn(0);
  PetscCall(DMGetLocalSection(dm, &lsec));
  PetscCall(DMGetCoordinatesLocal(dm, &coords));
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
    PetscInt        nv, vert[4];
    PetscReal       X[4][3], n[3], w[4] = {0, 0, 0, 0}, len;
    char            what[32];

    if (PetscBTLookup(notmine, face)) continue;
    PetscCall(PetscSNPrintf(what, sizeof(what), "surface %" PetscInt_FMT, id));
    PetscCall(MBCBodyFaceCorners(body, face, x, what, vert, X, &nv, n));
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
