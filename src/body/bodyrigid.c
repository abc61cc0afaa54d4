/* Rigid-body modes a body's supports leave free, for a static analysis treated as FETI does:
   with R the free modes, K u = f has a solution only if R^T f = 0, and then u = K^+ f + R alpha.
   K^+ is a generalised inverse: K with as many DOFs held at zero as there are free modes (chosen
   so that R restricted to them is regular, hence K with them held is), factored once. */
#include <mbc/private/bodyimpl.h>
#include <petscblaslapack.h>

/* Owned DOFs on a contact surface (labels contact_master, contact_slave): mask[i] for local row i. */
static PetscErrorCode BodyContactDofs(MBCBody body, PetscBool mask[])
{
  const char  *labels[2] = {"contact_master", "contact_slave"};
  PetscSection gsec, lsec;
  PetscInt     rstart;

  PetscFunctionBegin;
  PetscCall(DMGetGlobalSection(body->dm, &gsec));
  PetscCall(DMGetLocalSection(body->dm, &lsec));
  PetscCall(VecGetOwnershipRange(body->u, &rstart, NULL));
  for (PetscInt side = 0; side < 2; side++) {
    DMLabel label;
    IS      vals;
    PetscInt nv;
    const PetscInt *v;
    PetscCall(DMGetLabel(body->dm, labels[side], &label));
    if (!label) continue;
    PetscCall(DMLabelGetValueIS(label, &vals));
    PetscCall(ISGetLocalSize(vals, &nv));
    PetscCall(ISGetIndices(vals, &v));
    for (PetscInt k = 0; k < nv; k++) {
      IS              faceIS;
      const PetscInt *faces;
      PetscInt        nfaces;
      PetscCall(DMLabelGetStratumIS(label, v[k], &faceIS));
      if (!faceIS) continue;
      PetscCall(ISGetLocalSize(faceIS, &nfaces));
      PetscCall(ISGetIndices(faceIS, &faces));
      for (PetscInt f = 0; f < nfaces; f++) {
        PetscInt *closure = NULL, nclosure;
        PetscCall(DMPlexGetTransitiveClosure(body->dm, faces[f], PETSC_TRUE, &nclosure, &closure));
        for (PetscInt p = 0; p < 2 * nclosure; p += 2) {
          PetscInt off, dof;
          PetscCall(PetscSectionGetDof(lsec, closure[p], &dof));
          if (!dof) continue; /* the face's nodes */
          PetscCall(PetscSectionGetOffset(gsec, closure[p], &off));
          if (off < 0) continue; /* owned by another rank */
          for (PetscInt d = 0; d < 3; d++) mask[off + d - rstart] = PETSC_TRUE;
        }
        PetscCall(DMPlexRestoreTransitiveClosure(body->dm, faces[f], PETSC_TRUE, &nclosure, &closure));
      }
      PetscCall(ISRestoreIndices(faceIS, &faces));
      PetscCall(ISDestroy(&faceIS));
    }
    PetscCall(ISRestoreIndices(vals, &v));
    PetscCall(ISDestroy(&vals));
  }
  PetscFunctionReturn(0);
}

/* modes[]: the six rigid motions of the body, orthonormal (translations, then rotations about x, y,
   z), from its vertex coordinates; DMPlexCreateRigidBody projects the same functions through the
   FE machinery: 3.3 of the 198k dam's 45 s. The rotations are taken about the vertices' centroid,
   which the orthogonalisation against the translations gives anyway; the rounding stays that of
   the body's size, not of its distance from the origin. Collective on the body. */
static PetscErrorCode BodyRigidBasis(MBCBody body, Vec modes[6])
{
  PetscSection       lsec, gsec;
  Vec                coords, loc;
  const PetscScalar *x;
  PetscInt           vStart, vEnd;
  PetscReal          c[4] = {0, 0, 0, 0};

  PetscFunctionBegin;
  PetscCall(DMGetLocalSection(body->dm, &lsec));
  PetscCall(DMGetGlobalSection(body->dm, &gsec));
  PetscCall(DMGetCoordinatesLocal(body->dm, &coords));
  PetscCall(DMPlexGetChart(body->dm, &vStart, &vEnd)); /* every node: the vertices and tet10's edges */
  PetscCall(VecGetArrayRead(coords, &x));
  for (PetscInt v = vStart; v < vEnd; v++) { /* the centroid of the owned nodes, over the ranks */
    PetscInt  goff, dof;
    PetscReal X[3];
    PetscCall(PetscSectionGetDof(lsec, v, &dof));
    if (dof < 3) continue;
    PetscCall(PetscSectionGetOffset(gsec, v, &goff));
    if (goff < 0) continue;
    PetscCall(MBCBodyPointCoordinates(body, v, x, X));
    for (PetscInt d = 0; d < 3; d++) c[d] += X[d];
    c[3] += 1;
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, c, 4, MPIU_REAL, MPIU_SUM, body->comm));
  PetscCall(DMGetLocalVector(body->dm, &loc));
  for (PetscInt m = 0; m < 6; m++) {
    PetscScalar *l;
    PetscCall(VecZeroEntries(loc));
    PetscCall(VecGetArray(loc, &l));
    for (PetscInt v = vStart; v < vEnd; v++) {
      PetscInt  off, dof;
      PetscReal X[3];
      PetscCall(PetscSectionGetDof(lsec, v, &dof));
      if (dof < 3) continue;
      PetscCall(PetscSectionGetOffset(lsec, v, &off));
      PetscCall(MBCBodyPointCoordinates(body, v, x, X));
      for (PetscInt d = 0; d < 3; d++) X[d] -= c[d] / c[3];
      if (m < 3) l[off + m] = 1;
      else { /* e_k x X */
        const PetscInt k = m - 3, i = (k + 1) % 3, j = (k + 2) % 3;
        l[off + i] = -X[j];
        l[off + j] = X[i];
      }
    }
    PetscCall(VecRestoreArray(loc, &l));
    PetscCall(VecDuplicate(body->u, &modes[m]));
    PetscCall(DMLocalToGlobal(body->dm, loc, INSERT_VALUES, modes[m]));
  }
  PetscCall(DMRestoreLocalVector(body->dm, &loc));
  PetscCall(VecRestoreArrayRead(coords, &x));
  for (PetscInt m = 0; m < 6; m++) { /* modified Gram-Schmidt, as DMPlexCreateRigidBody */
    PetscScalar dots[6];
    PetscCall(VecNormalize(modes[m], NULL));
    if (m == 5) break;
    PetscCall(VecMDot(modes[m], 5 - m, modes + m + 1, dots));
    for (PetscInt j = m + 1; j < 6; j++) PetscCall(VecAXPY(modes[j], -dots[j - m - 1], modes[m]));
  }
  PetscFunctionReturn(0);
}

/* Springs to the ground hold some of the modes the supports leave free: of the free combinations
   (the columns a of V with ev[a] < 1e-12), those K does not annihilate. S = R^T K R over them
   (the elements' part is rounding, eps |K|), its eigenvectors with eigenvalues below 1e-9 max
   diag K stay free: V and ev are rewritten to hold them (ev 0) and the others (ev 1), *k their count. */
static PetscErrorCode BodySpringHeldModes(MBCBody body, Vec modes[6], PetscScalar V[36], PetscReal ev[6], PetscInt *k)
{
  PetscInt     f[6], nf = 0;
  PetscScalar  S[36], W[36], work[200], out[36];
  PetscReal    es[6], dmax;
  PetscBLASInt n, lwork = 200, info;
  Vec          R, KR, d;

  PetscFunctionBegin;
  for (PetscInt a = 0; a < 6; a++)
    if (PetscRealPart(ev[a]) < 1e-12) f[nf++] = a;
  PetscCall(VecDuplicate(body->u, &R));
  PetscCall(VecDuplicate(body->u, &KR));
  PetscCall(VecDuplicate(body->u, &d));
  PetscCall(MatGetDiagonal(body->K, d));
  PetscCall(VecNorm(d, NORM_INFINITY, &dmax));
  for (PetscInt i = 0; i < nf; i++) {
    Vec Rj;
    PetscCall(VecZeroEntries(R));
    for (PetscInt b = 0; b < 6; b++) PetscCall(VecAXPY(R, V[f[i] * 6 + b], modes[b]));
    PetscCall(MatMult(body->K, R, KR));
    PetscCall(VecDuplicate(R, &Rj));
    for (PetscInt j = 0; j < nf; j++) {
      PetscScalar s;
      PetscCall(VecZeroEntries(Rj));
      for (PetscInt b = 0; b < 6; b++) PetscCall(VecAXPY(Rj, V[f[j] * 6 + b], modes[b]));
      PetscCall(VecDot(KR, Rj, &s));
      S[i * nf + j] = s;
    }
    PetscCall(VecDestroy(&Rj));
  }
  PetscCall(VecDestroy(&R));
  PetscCall(VecDestroy(&KR));
  PetscCall(VecDestroy(&d));
  PetscCall(PetscBLASIntCast(nf, &n));
  PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "U", &n, S, &n, es, work, &lwork, &info));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "LAPACK syev failed (%d) on body '%s''s spring-held modes", (int)info, body->name);
  /* new rows of V: the free combinations first (ev 0), then the held (ev 1), the constrained ones as they were */
  for (PetscInt a = 0; a < 36; a++) out[a] = V[a];
  {
    PetscInt row = 0, kept = 0;
    for (PetscInt pass = 0; pass < 2; pass++)
      for (PetscInt i = 0; i < nf; i++) {
        const PetscBool is_free = (PetscBool)(es[i] < 1e-9 * dmax);
        if (is_free != (pass == 0)) continue;
        for (PetscInt b = 0; b < 6; b++) {
          W[b] = 0;
          for (PetscInt j = 0; j < nf; j++) W[b] += S[i * nf + j] * V[f[j] * 6 + b];
        }
        for (PetscInt b = 0; b < 6; b++) out[f[row] * 6 + b] = W[b];
        ev[f[row]] = is_free ? 0 : 1;
        row++;
        kept += is_free;
      }
    *k = kept;
  }
  for (PetscInt a = 0; a < 36; a++) V[a] = out[a];
  PetscFunctionReturn(0);
}

/* body->rigid: the free modes (orthonormal), body->fix_rows: the DOFs held in K^+. The six rigid
   modes of the mesh, combined by the eigenvectors of C^T C (C: the modes on the prescribed DOFs)
   whose eigenvalues vanish: those combinations do not move any prescribed DOF. */
PetscErrorCode MBCBodyRigidModes(MBCBody body)
{
  Vec                modes[6];
  PetscInt           nm = 6, rstart, rend, k = 0;
  PetscScalar        CtC[36], V[36], work[200];
  PetscReal          ev[6];
  PetscBLASInt       n6, lwork = 200, info;
  const PetscScalar *mv[6];

  PetscFunctionBegin;
  PetscCall(MBCBodyRigidModesDestroy(body));
  if (body->desc.rigid) { /* a rigid body: its free components, nothing to hold in K^+ = 0 */
    PetscCall(MBCBodyRigidFreeModes(body));
    PetscFunctionReturn(0);
  }
  PetscCall(BodyRigidBasis(body, modes));
  PetscCall(VecGetOwnershipRange(body->u, &rstart, &rend));
  for (PetscInt a = 0; a < nm; a++) PetscCall(VecGetArrayRead(modes[a], &mv[a]));
  for (PetscInt a = 0; a < nm * nm; a++) CtC[a] = 0;
  for (PetscInt i = 0; i < body->nbc; i++)
    for (PetscInt a = 0; a < nm; a++)
      for (PetscInt b = 0; b < nm; b++) CtC[a * nm + b] += mv[a][body->bc_rows[i] - rstart] * mv[b][body->bc_rows[i] - rstart];
  for (PetscInt a = 0; a < nm; a++) PetscCall(VecRestoreArrayRead(modes[a], &mv[a]));
  PetscCall(MPIU_Allreduce(CtC, V, nm * nm, MPIU_SCALAR, MPIU_SUM, body->comm));
  PetscCall(PetscBLASIntCast(nm, &n6));
  PetscCallBLAS("LAPACKsyev", LAPACKsyev_("V", "U", &n6, V, &n6, ev, work, &lwork, &info));
  PetscCheck(!info, PETSC_COMM_SELF, PETSC_ERR_LIB, "LAPACK syev failed (%d) on body '%s''s rigid modes", (int)info, body->name);
  /* the modes are unit vectors: an eigenvalue is the share of a combination's norm on prescribed
     DOFs, 0 for a free motion, at least ~1/N for one that moves a single prescribed DOF */
  for (PetscInt a = 0; a < nm; a++)
    if (PetscRealPart(ev[a]) < 1e-12) k++;
  if (k && MBCBodyHasSprings(body)) PetscCall(BodySpringHeldModes(body, modes, V, ev, &k));
  body->nrigid = k;
  if (k) {
    PetscReal   *piv, pv;
    PetscBool   *oncontact;
    PetscScalar *rv;
    Vec         *W;
    PetscCall(PetscMalloc1(k, &body->rigid));
    PetscCall(PetscMalloc3(k, &body->fix_rows, k, &body->erigid, k, &body->frigid));
    for (PetscInt j = 0, a = 0; a < nm; a++) {
      if (!(PetscRealPart(ev[a]) < 1e-12)) continue;
      PetscCall(VecDuplicate(body->u, &body->rigid[j]));
      PetscCall(VecZeroEntries(body->rigid[j]));
      for (PetscInt b = 0; b < nm; b++) PetscCall(VecAXPY(body->rigid[j], V[a * nm + b], modes[b]));
      PetscCall(MBCBodySetConstrainedRows(body, NULL, body->rigid[j])); /* exactly 0 there */
      j++;
    }
    /* the held DOFs: elimination with full pivoting over the rows of R, off the contact surfaces
       where a row nearly as good exists (held DOFs on a contact face made the Newton solve of a
       one-element block stall: measured, cause not found) */
    PetscCall(VecDuplicateVecs(body->u, k, &W));
    {
      PetscInt n;
      PetscCall(VecGetLocalSize(body->u, &n));
      PetscCall(PetscCalloc1(n + 1, &oncontact));
      PetscCall(BodyContactDofs(body, oncontact));
    }
    for (PetscInt j = 0; j < k; j++) PetscCall(VecCopy(body->rigid[j], W[j]));
    PetscCall(PetscMalloc1(k, &piv));
    for (PetscInt p = 0; p < k; p++) {
      struct {
        PetscReal v;
        PetscInt  row;
      } loc = {-1, -1}, glob;
      PetscInt n;
      PetscCall(VecGetLocalSize(W[p], &n));
      PetscCall(VecGetArray(W[p], &rv));
      {
        PetscReal mx = 0;
        for (PetscInt i = 0; i < n; i++) mx = PetscMax(mx, PetscAbsScalar(rv[i]));
        PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &mx, 1, MPIU_REAL, MPI_MAX, body->comm));
        for (PetscInt i = 0; i < n; i++) /* the largest off the contact surfaces, if it is at least half the largest */
          if (!oncontact[i] && PetscAbsScalar(rv[i]) > loc.v && PetscAbsScalar(rv[i]) >= 0.5 * mx) loc.v = PetscAbsScalar(rv[i]), loc.row = rstart + i;
        {
          PetscReal any = loc.v, anyg;
          PetscCall(MPIU_Allreduce(&any, &anyg, 1, MPIU_REAL, MPI_MAX, body->comm));
          if (anyg < 0) /* none: the largest anywhere */
            for (PetscInt i = 0; i < n; i++)
              if (PetscAbsScalar(rv[i]) > loc.v) loc.v = PetscAbsScalar(rv[i]), loc.row = rstart + i;
        }
      }
      PetscCall(VecRestoreArray(W[p], &rv));
      {
        PetscReal   in[2] = {loc.v, (PetscReal)loc.row}, out[2];
        PetscMPIInt size;
        PetscCallMPI(MPI_Comm_size(body->comm, &size));
        out[0] = in[0], out[1] = in[1];
        if (size > 1) { /* the largest entry and its row, the same on every rank (ties: the lowest rank's) */
          PetscReal *all;
          PetscCall(PetscMalloc1(2 * size, &all));
          PetscCallMPI(MPI_Allgather(in, 2, MPIU_REAL, all, 2, MPIU_REAL, body->comm));
          out[0] = -1, out[1] = -1;
          for (PetscMPIInt r = 0; r < size; r++)
            if (all[2 * r] > out[0]) out[0] = all[2 * r], out[1] = all[2 * r + 1];
          PetscCall(PetscFree(all));
        }
        glob.v = out[0], glob.row = (PetscInt)out[1];
      }
      PetscCheck(glob.v > 0, body->comm, PETSC_ERR_PLIB, "Body '%s': rigid mode %" PetscInt_FMT " vanishes", body->name, p);
      body->fix_rows[p] = glob.row;
      piv[p]            = glob.v;
      /* W_q -= (W_q[row] / W_p[row]) W_p for the later modes */
      for (PetscInt q = p + 1; q < k; q++) {
        PetscScalar wq = 0, wp = 0;
        if (glob.row >= rstart && glob.row < rend) {
          PetscCall(VecGetValues(W[q], 1, &glob.row, &wq));
          PetscCall(VecGetValues(W[p], 1, &glob.row, &wp));
        }
        {
          PetscScalar in[2] = {wq, wp}, out[2];
          PetscCall(MPIU_Allreduce(in, out, 2, MPIU_SCALAR, MPIU_SUM, body->comm));
          pv = PetscRealPart(out[0] / out[1]);
        }
        PetscCall(VecAXPY(W[q], -pv, W[p]));
      }
    }
    PetscCall(PetscFree(piv));
    PetscCall(PetscFree(oncontact));
    PetscCall(VecDestroyVecs(k, &W));
    /* owned held rows, sorted, for MatZeroRowsColumns and the right sides */
    body->nfix = 0;
    for (PetscInt p = 0; p < k; p++)
      if (body->fix_rows[p] >= rstart && body->fix_rows[p] < rend) body->fix_rows[body->nfix++] = body->fix_rows[p];
    PetscCall(PetscSortInt(body->nfix, body->fix_rows));
  }
  for (PetscInt m = 0; m < nm; m++) PetscCall(VecDestroy(&modes[m]));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCBodyRigidModesDestroy(MBCBody body)
{
  PetscFunctionBegin;
  if (body->Ainv) PetscCall(MatSetNullSpace(body->Ainv, NULL)); /* the modes it held go */
  for (PetscInt j = 0; j < body->nrigid; j++) PetscCall(VecDestroy(&body->rigid[j]));
  PetscCall(PetscFree(body->rigid));
  PetscCall(PetscFree3(body->fix_rows, body->erigid, body->frigid));
  body->nrigid = body->nfix = 0;
  PetscFunctionReturn(0);
}

/* Rows held by K^+ set to zero in a right side (a Vec), or in the columns of a dense Mat. */
PetscErrorCode MBCBodyZeroHeldRows(MBCBody body, Vec v, Mat X)
{
  PetscInt rstart;

  PetscFunctionBegin;
  if (!body->nfix) PetscFunctionReturn(0);
  if (v) {
    PetscScalar *a;
    PetscCall(VecGetOwnershipRange(v, &rstart, NULL));
    PetscCall(VecGetArray(v, &a));
    for (PetscInt i = 0; i < body->nfix; i++) a[body->fix_rows[i] - rstart] = 0;
    PetscCall(VecRestoreArray(v, &a));
  }
  if (X) {
    PetscScalar *a;
    PetscInt     lda, n;
    PetscCall(MatGetOwnershipRange(X, &rstart, NULL));
    PetscCall(MatGetSize(X, NULL, &n));
    PetscCall(MatDenseGetLDA(X, &lda));
    PetscCall(MatDenseGetArray(X, &a));
    for (PetscInt j = 0; j < n; j++)
      for (PetscInt i = 0; i < body->nfix; i++) a[(size_t)j * lda + body->fix_rows[i] - rstart] = 0;
    PetscCall(MatDenseRestoreArray(X, &a));
  }
  PetscFunctionReturn(0);
}
