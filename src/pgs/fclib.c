/* FCLIB interchange (layout: shared/benchmarks/fclib/README.md) with the HDF5 C API: Debian's
   libfclib links the serial HDF5, which must not share a process with PETSc's MPI HDF5. */
#include <mbc/private/pgsimpl.h>
#include <mbc/private/h5util.h>

static PetscErrorCode H5ReadArray(hid_t loc, const char *file, const char *path, hid_t type, void *buf, hsize_t *n)
{
  hid_t   d, sp;
  hsize_t dims[2] = {0, 0};
  int     nd;

  PetscFunctionBegin;
  PetscCheck(H5Lexists(loc, path, H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: dataset %s is missing", file, path);
  d  = H5Dopen2(loc, path, H5P_DEFAULT);
  sp = H5Dget_space(d);
  nd = H5Sget_simple_extent_ndims(sp);
  H5Sget_simple_extent_dims(sp, dims, NULL);
  *n = nd == 0 ? 1 : dims[0] * (nd > 1 ? dims[1] : 1);
  if (buf) PetscCheck(H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "FCLIB file %s: cannot read %s", file, path);
  H5Sclose(sp);
  H5Dclose(d);
  PetscFunctionReturn(0);
}

static PetscErrorCode H5ReadInt1(hid_t loc, const char *file, const char *path, PetscInt *v)
{
  long long x;
  hsize_t   n;

  PetscFunctionBegin;
  PetscCall(H5ReadArray(loc, file, path, H5T_NATIVE_LLONG, NULL, &n));
  PetscCheck(n == 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: %s must hold one integer", file, path);
  PetscCall(H5ReadArray(loc, file, path, H5T_NATIVE_LLONG, &x, &n));
  *v = (PetscInt)x;
  PetscFunctionReturn(0);
}

/* Allocates and reads a dataset "<group>/<name>" (n entries of size elem). */
static PetscErrorCode H5ReadAlloc(hid_t loc, const char *file, const char *group, const char *name, hid_t type, size_t elem, void **buf, hsize_t *n)
{
  char path[256];

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/%s", group, name));
  PetscCall(H5ReadArray(loc, file, path, type, NULL, n));
  PetscCall(PetscMalloc(PetscMax(*n, 1) * elem, buf));
  PetscCall(H5ReadArray(loc, file, path, type, *buf, n));
  PetscFunctionReturn(0);
}

/* A FCLIB matrix group (m, n, nz, p, i, x): nz = -2 compressed rows, -1 compressed columns,
   >= 0 triplets (i row, p column; duplicates add). */
static PetscErrorCode ReadMatrix(hid_t loc, const char *file, const char *name, Mat *A)
{
  char      path[256];
  PetscInt  m, n, nz, cnt, *row, *col, *nnz;
  long long *p, *ix;
  double    *x;
  hsize_t    np, ni, nx;

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/m", name));
  PetscCall(H5ReadInt1(loc, file, path, &m));
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/n", name));
  PetscCall(H5ReadInt1(loc, file, path, &n));
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/nz", name));
  PetscCall(H5ReadInt1(loc, file, path, &nz));
  PetscCheck(m >= 0 && n >= 0 && nz >= -2, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s has m = %" PetscInt_FMT ", n = %" PetscInt_FMT ", nz = %" PetscInt_FMT, file, name, m, n, nz);
  PetscCall(H5ReadAlloc(loc, file, name, "p", H5T_NATIVE_LLONG, sizeof(long long), (void **)&p, &np));
  PetscCall(H5ReadAlloc(loc, file, name, "i", H5T_NATIVE_LLONG, sizeof(long long), (void **)&ix, &ni));
  PetscCall(H5ReadAlloc(loc, file, name, "x", H5T_NATIVE_DOUBLE, sizeof(double), (void **)&x, &nx));
  cnt = nz >= 0 ? nz : (PetscInt)(nz == -2 ? p[m] : p[n]);
  PetscCheck((hsize_t)cnt <= nx && (hsize_t)cnt <= ni && (nz >= 0 ? (hsize_t)cnt <= np : np >= (hsize_t)((nz == -2 ? m : n) + 1)), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s has inconsistent sizes", file, name);
  PetscCall(PetscMalloc2(cnt, &row, cnt, &col));
  PetscCall(PetscCalloc1(m, &nnz));
  for (PetscInt k = 0, e = 0; nz < 0 && k < (nz == -2 ? m : n); k++)
    for (long long j = p[k]; j < p[k + 1]; j++, e++) {
      row[e] = nz == -2 ? k : (PetscInt)ix[j];
      col[e] = nz == -2 ? (PetscInt)ix[j] : k;
    }
  for (PetscInt e = 0; nz >= 0 && e < cnt; e++) {
    row[e] = (PetscInt)ix[e];
    col[e] = (PetscInt)p[e];
  }
  for (PetscInt e = 0; e < cnt; e++) {
    PetscCheck(row[e] >= 0 && row[e] < m && col[e] >= 0 && col[e] < n, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s entry (%" PetscInt_FMT ", %" PetscInt_FMT ") outside %" PetscInt_FMT " x %" PetscInt_FMT, file, name, row[e], col[e], m, n);
    nnz[row[e]]++;
  }
  for (PetscInt k = 0; k < m; k++) nnz[k] = PetscMin(nnz[k], n);
  PetscCall(MatCreateSeqAIJ(PETSC_COMM_SELF, m, n, 0, nnz, A));
  for (PetscInt e = 0; e < cnt; e++) PetscCall(MatSetValue(*A, row[e], col[e], x[e], ADD_VALUES));
  PetscCall(MatAssemblyBegin(*A, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*A, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree(nnz));
  PetscCall(PetscFree2(row, col));
  PetscCall(PetscFree(p));
  PetscCall(PetscFree(ix));
  PetscCall(PetscFree(x));
  PetscFunctionReturn(0);
}

static PetscErrorCode ReadVector(hid_t loc, const char *file, const char *path, PetscInt n, Vec *v)
{
  hsize_t      len;
  PetscScalar *a;

  PetscFunctionBegin;
  PetscCall(H5ReadArray(loc, file, path, H5T_NATIVE_DOUBLE, NULL, &len));
  PetscCheck((PetscInt)len == n, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: %s has %llu entries, expected %" PetscInt_FMT, file, path, (unsigned long long)len, n);
  PetscCall(VecCreateSeq(PETSC_COMM_SELF, n, v));
  PetscCall(VecGetArray(*v, &a));
  PetscCall(H5ReadArray(loc, file, path, H5T_NATIVE_DOUBLE, a, &len));
  PetscCall(VecRestoreArray(*v, &a));
  PetscFunctionReturn(0);
}

/* A global problem M v = H r + f, u = H^T v + w condensed to u = W r + q:
   W = H^T M^-1 H, q = H^T M^-1 f + w (one LU of M by MUMPS, one multi-right-hand-side solve). */
static PetscErrorCode CondenseGlobal(hid_t g, const char *file, MBCFrictionProblem *fp)
{
  Mat           M, H, Hd, X, F, W;
  Vec           f, w, y;
  IS            rperm, cperm;
  MatFactorInfo info;
  PetscInt      m, n;

  PetscFunctionBegin;
  PetscCall(ReadMatrix(g, file, "M", &M));
  PetscCall(ReadMatrix(g, file, "H", &H));
  PetscCall(MatGetSize(H, &m, &n));
  PetscCheck(n % 3 == 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: H has %" PetscInt_FMT " columns, not 3 per contact", file, n);
  fp->nc = n / 3;
  PetscCall(MBCFrictionProblemSetBlocks(fp, NULL));
  PetscCall(ReadVector(g, file, "vectors/f", m, &f));
  PetscCall(ReadVector(g, file, "vectors/w", n, &w));
  PetscCall(MatGetFactor(M, MATSOLVERMUMPS, MAT_FACTOR_LU, &F));
  PetscCall(MatGetOrdering(M, MATORDERINGNATURAL, &rperm, &cperm));
  PetscCall(MatFactorInfoInitialize(&info));
  PetscCall(MatLUFactorSymbolic(F, M, rperm, cperm, &info));
  PetscCall(MatLUFactorNumeric(F, M, &info));
  PetscCall(MatConvert(H, MATSEQDENSE, MAT_INITIAL_MATRIX, &Hd));
  PetscCall(MatDuplicate(Hd, MAT_DO_NOT_COPY_VALUES, &X));
  PetscCall(MatMatSolve(F, Hd, X));
  PetscCall(MatTransposeMatMult(Hd, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &W));
  PetscCall(MatConvert(W, MATSEQAIJ, MAT_INITIAL_MATRIX, &fp->W));
  PetscCall(VecDuplicate(f, &y));
  PetscCall(MatSolve(F, f, y));
  PetscCall(VecDuplicate(w, &fp->q));
  PetscCall(MatMultTranspose(H, y, fp->q));
  PetscCall(VecAXPY(fp->q, 1.0, w));
  PetscCall(ISDestroy(&rperm));
  PetscCall(ISDestroy(&cperm));
  PetscCall(MatDestroy(&W));
  PetscCall(MatDestroy(&X));
  PetscCall(MatDestroy(&Hd));
  PetscCall(MatDestroy(&F));
  PetscCall(MatDestroy(&M));
  PetscCall(MatDestroy(&H));
  PetscCall(VecDestroy(&f));
  PetscCall(VecDestroy(&w));
  PetscCall(VecDestroy(&y));
  PetscFunctionReturn(0);
}

/* Reads an FCLIB local problem, or a global one condensed to local form. */
PetscErrorCode MBCFclibRead(const char file[], MBCFrictionProblem *fp, PetscBool *global)
{
  hid_t     h5, g;
  PetscBool exists;
  hsize_t   nmu;
  PetscInt  n;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(fp, sizeof(*fp)));
  PetscCall(PetscTestFile(file, 'r', &exists));
  PetscCheck(exists, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "FCLIB file %s does not exist or cannot be read", file);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  PetscCheck(H5Fis_hdf5(file) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s is not an HDF5 file", file);
  h5 = H5Fopen(file, H5F_ACC_RDONLY, H5P_DEFAULT);
  PetscCheck(h5 >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot open FCLIB file %s", file);
  *global = (PetscBool)(H5Lexists(h5, "fclib_global", H5P_DEFAULT) > 0);
  PetscCheck(*global || H5Lexists(h5, "fclib_local", H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s has neither /fclib_local nor /fclib_global", file);
  g = H5Gopen2(h5, *global ? "fclib_global" : "fclib_local", H5P_DEFAULT);
  if (H5Lexists(g, "spacedim", H5P_DEFAULT) > 0) {
    PetscInt dim;
    PetscCall(H5ReadInt1(g, file, "spacedim", &dim));
    PetscCheck(dim == 3, PETSC_COMM_SELF, PETSC_ERR_SUP, "FCLIB file %s: spacedim %" PetscInt_FMT "; mbcontact solves 3D problems", file, dim);
  }
  if (*global) PetscCall(CondenseGlobal(g, file, fp));
  else {
    PetscCall(ReadMatrix(g, file, "W", &fp->W));
    PetscCall(MatGetSize(fp->W, &n, NULL));
    PetscCheck(n % 3 == 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: W has %" PetscInt_FMT " rows, not 3 per contact", file, n);
    fp->nc = n / 3;
    PetscCall(MBCFrictionProblemSetBlocks(fp, NULL));
    PetscCall(ReadVector(g, file, "vectors/q", n, &fp->q));
  }
  PetscCall(H5ReadArray(g, file, "vectors/mu", H5T_NATIVE_DOUBLE, NULL, &nmu));
  PetscCheck((PetscInt)nmu == fp->nc, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: %llu friction coefficients for %" PetscInt_FMT " contacts", file, (unsigned long long)nmu, fp->nc);
  PetscCall(PetscMalloc1(fp->nc, &fp->mu));
  PetscCall(H5ReadArray(g, file, "vectors/mu", H5T_NATIVE_DOUBLE, fp->mu, &nmu));
  for (PetscInt i = 0; i < fp->nc; i++) PetscCheck(fp->mu[i] >= 0 && !PetscIsInfOrNanReal(fp->mu[i]), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: contact %" PetscInt_FMT " has friction coefficient %g", file, i, (double)fp->mu[i]);
  PetscCall(PetscStrncpy(fp->title, file, sizeof(fp->title)));
  H5Gclose(g);
  H5Fclose(h5);
  PetscFunctionReturn(0);
}

/* Writes u = W r + q as an FCLIB local problem (W in compressed rows), with r, u (when given)
   as /solution/r and /solution/u. FCLIB contacts are 3-blocks: a frictionless 1-block is written
   as a 3-block with mu = 0, q_t = 0 and W_tt = W_nn I (so r_t = u_t = 0 solve it: the same problem). */
PetscErrorCode MBCFclibWriteLocal(const char file[], MBCFrictionProblem *fp, Vec r, Vec u)
{
  hid_t              h5, g, gw, gv, gs;
  PetscInt           n = 3 * fp->nc, m = fp->off[fp->nc], nnz = 0, *map;
  int               *p, *ix, dims[4];
  double            *x, *vec;
  const PetscScalar *a;

  PetscFunctionBegin;
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  h5 = H5Fcreate(file, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  PetscCheck(h5 >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot create FCLIB file %s", file);
  PetscCall(PetscMalloc1(m, &map)); /* row of fp -> row of the 3-block layout */
  for (PetscInt i = 0; i < fp->nc; i++)
    for (PetscInt d = 0; d < fp->off[i + 1] - fp->off[i]; d++) map[fp->off[i] + d] = 3 * i + d;
  for (PetscInt row = 0; row < m; row++) {
    PetscInt ncols;
    PetscCall(MatGetRow(fp->W, row, &ncols, NULL, NULL));
    nnz += ncols;
    PetscCall(MatRestoreRow(fp->W, row, &ncols, NULL, NULL));
  }
  nnz += n - m; /* the two tangential diagonal entries of each frictionless contact */
  PetscCall(PetscMalloc3(n + 1, &p, nnz, &ix, nnz, &x));
  PetscCall(PetscCalloc1(n, &vec));
  p[0] = 0;
  for (PetscInt i = 0; i < fp->nc; i++) {
    const PetscInt o = fp->off[i], dim = fp->off[i + 1] - o;
    PetscScalar    wnn;
    PetscCall(MatGetValue(fp->W, o, o, &wnn));
    for (PetscInt d = 0; d < 3; d++) {
      const PetscInt R = 3 * i + d;
      if (d < dim) { /* columns stay sorted: map is increasing */
        PetscInt           ncols;
        const PetscInt    *cols;
        const PetscScalar *vals;
        PetscCall(MatGetRow(fp->W, o + d, &ncols, &cols, &vals));
        for (PetscInt k = 0; k < ncols; k++) {
          ix[p[R] + k] = (int)map[cols[k]];
          x[p[R] + k]  = PetscRealPart(vals[k]);
        }
        p[R + 1] = p[R] + (int)ncols;
        PetscCall(MatRestoreRow(fp->W, o + d, &ncols, &cols, &vals));
      } else {
        ix[p[R]] = (int)R;
        x[p[R]]  = PetscRealPart(wnn);
        p[R + 1] = p[R] + 1;
      }
    }
  }
  g  = H5Gcreate2(h5, "fclib_local", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  gw = H5Gcreate2(g, "W", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  dims[0] = (int)n, dims[1] = (int)n, dims[2] = -2, dims[3] = p[n];
  PetscCall(MBCH5WriteArray(gw, "m", H5T_NATIVE_INT, 1, 1, &dims[0]));
  PetscCall(MBCH5WriteArray(gw, "n", H5T_NATIVE_INT, 1, 1, &dims[1]));
  PetscCall(MBCH5WriteArray(gw, "nz", H5T_NATIVE_INT, 1, 1, &dims[2]));
  PetscCall(MBCH5WriteArray(gw, "nzmax", H5T_NATIVE_INT, 1, 1, &dims[3]));
  PetscCall(MBCH5WriteArray(gw, "p", H5T_NATIVE_INT, n + 1, 1, p));
  PetscCall(MBCH5WriteArray(gw, "i", H5T_NATIVE_INT, (PetscInt)p[n], 1, ix));
  PetscCall(MBCH5WriteArray(gw, "x", H5T_NATIVE_DOUBLE, (PetscInt)p[n], 1, x));
  H5Gclose(gw);
  gv = H5Gcreate2(g, "vectors", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  PetscCall(VecGetArrayRead(fp->q, &a));
  for (PetscInt row = 0; row < m; row++) vec[map[row]] = PetscRealPart(a[row]);
  PetscCall(VecRestoreArrayRead(fp->q, &a));
  PetscCall(MBCH5WriteArray(gv, "q", H5T_NATIVE_DOUBLE, n, 1, vec));
  PetscCall(MBCH5WriteArray(gv, "mu", H5T_NATIVE_DOUBLE, fp->nc, 1, fp->mu));
  H5Gclose(gv);
  {
    int sd = 3;
    PetscCall(MBCH5WriteArray(g, "spacedim", H5T_NATIVE_INT, 1, 1, &sd));
  }
  H5Gclose(g);
  if (r && u) {
    const char *names[2] = {"r", "u"};
    Vec         vs[2]    = {r, u};
    gs = H5Gcreate2(h5, "solution", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    for (int k = 0; k < 2; k++) {
      PetscCall(PetscArrayzero(vec, n));
      PetscCall(VecGetArrayRead(vs[k], &a));
      for (PetscInt row = 0; row < m; row++) vec[map[row]] = PetscRealPart(a[row]);
      PetscCall(VecRestoreArrayRead(vs[k], &a));
      PetscCall(MBCH5WriteArray(gs, names[k], H5T_NATIVE_DOUBLE, n, 1, vec));
    }
    H5Gclose(gs);
  }
  H5Fclose(h5);
  PetscCall(PetscFree3(p, ix, x));
  PetscCall(PetscFree(vec));
  PetscCall(PetscFree(map));
  PetscFunctionReturn(0);
}

/* r from /solution/r of an FCLIB file (a warm start). */
PetscErrorCode MBCFclibReadSolution(const char file[], Vec r)
{
  hid_t        h5;
  hsize_t      n;
  PetscInt     len;
  PetscScalar *a;

  PetscFunctionBegin;
  h5 = H5Fopen(file, H5F_ACC_RDONLY, H5P_DEFAULT);
  PetscCheck(h5 >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot open FCLIB file %s", file);
  PetscCall(H5ReadArray(h5, file, "solution/r", H5T_NATIVE_DOUBLE, NULL, &n));
  PetscCall(VecGetSize(r, &len));
  PetscCheck((PetscInt)n == len, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: solution/r has %llu entries, expected %" PetscInt_FMT, file, (unsigned long long)n, len);
  PetscCall(VecGetArray(r, &a));
  PetscCall(H5ReadArray(h5, file, "solution/r", H5T_NATIVE_DOUBLE, a, &n));
  PetscCall(VecRestoreArray(r, &a));
  H5Fclose(h5);
  PetscFunctionReturn(0);
}
