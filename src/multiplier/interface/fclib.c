/* FCLIB interchange (layout: shared/benchmarks/fclib/README.md) with the HDF5 C API: Debian's
   libfclib links the serial HDF5, which must not share a process with PETSc's MPI HDF5. */
#include <mbc/private/multiplierimpl.h>
#include <string.h>
#include <mbc/private/h5util.h>

/* Entries beyond this magnitude overflow the squares in the norms and the merit function. */
#define MBC_FCLIB_MAX_ABS 1e100

static PetscErrorCode H5ReadArray(hid_t loc, const char *file, const char *path, hid_t type, void *buf, hsize_t *n)
{
  hid_t       d, sp, t;
  hsize_t     dims[2] = {0, 0};
  int         nd;
  H5T_class_t cls;

  PetscFunctionBegin;
  PetscCheck(H5Lexists(loc, path, H5P_DEFAULT) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: dataset %s is missing", file, path);
  d = H5Dopen2(loc, path, H5P_DEFAULT);
  PetscCheck(d >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: %s is not a dataset", file, path);
  t   = H5Dget_type(d);
  cls = H5Tget_class(t);
  H5Tclose(t);
  sp = H5Dget_space(d);
  nd = H5Sget_simple_extent_ndims(sp);
  if (nd >= 0 && nd <= 2) H5Sget_simple_extent_dims(sp, dims, NULL);
  H5Sclose(sp);
  if (!(cls == H5T_INTEGER || cls == H5T_FLOAT) || nd < 0 || nd > 2) H5Dclose(d);
  PetscCheck(cls == H5T_INTEGER || cls == H5T_FLOAT, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: dataset %s does not hold numbers", file, path);
  PetscCheck(nd >= 0 && nd <= 2, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: dataset %s has %d dimensions (at most 2)", file, path, nd);
  *n = nd == 0 ? 1 : dims[0] * (nd > 1 ? dims[1] : 1);
  if (*n >= (hsize_t)PETSC_MAX_INT / 8) H5Dclose(d);
  PetscCheck(*n < (hsize_t)PETSC_MAX_INT / 8, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: dataset %s has %llu entries, more than this build of PETSc can index", file, path, (unsigned long long)*n);
  if (buf && *n && H5Dread(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) < 0) {
    H5Dclose(d);
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "FCLIB file %s: cannot read %s (truncated file?)", file, path);
  }
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
  /* PetscInt is 32-bit here: a larger size would be cut to another number */
  PetscCheck(x >= PETSC_MIN_INT && x <= PETSC_MAX_INT, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: %s = %lld is outside the range of a 32-bit integer", file, path, x);
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
   >= 0 triplets (i row, p column; duplicates add). The structure is checked before any use:
   p starts at 0 and never decreases, every index lies in the matrix, every value is finite. */
static PetscErrorCode ReadMatrix(hid_t loc, const char *file, const char *name, PetscInt mexp, Mat *A)
{
  char       path[256];
  PetscInt   m, n, nz, cnt, nouter, *row, *col, *nnz;
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
  PetscCheck(m >= 1 && n >= 1 && nz >= -2, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s has m = %" PetscInt_FMT ", n = %" PetscInt_FMT ", nz = %" PetscInt_FMT " (need m, n >= 1, nz >= -2)", file, name, m, n, nz);
  PetscCall(H5ReadAlloc(loc, file, name, "p", H5T_NATIVE_LLONG, sizeof(long long), (void **)&p, &np));
  PetscCall(H5ReadAlloc(loc, file, name, "i", H5T_NATIVE_LLONG, sizeof(long long), (void **)&ix, &ni));
  PetscCall(H5ReadAlloc(loc, file, name, "x", H5T_NATIVE_DOUBLE, sizeof(double), (void **)&x, &nx));
  nouter = nz == -2 ? m : n;
  if (nz < 0) {
    PetscCheck(np >= (hsize_t)nouter + 1, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s/p has %llu entries; compressed %s need %" PetscInt_FMT, file, name, (unsigned long long)np, nz == -2 ? "rows" : "columns", nouter + 1);
    PetscCheck(p[0] == 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s/p[0] = %lld, expected 0", file, name, p[0]);
    for (PetscInt k = 0; k < nouter; k++) PetscCheck(p[k + 1] >= p[k] && (hsize_t)p[k + 1] <= PetscMin(ni, nx), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s/p[%" PetscInt_FMT "] = %lld after %lld: p must not decrease nor pass the %llu entries of i and x", file, name, k + 1, p[k + 1], p[k], (unsigned long long)PetscMin(ni, nx));
    cnt = (PetscInt)p[nouter];
  } else {
    cnt = nz;
    PetscCheck((hsize_t)cnt <= nx && (hsize_t)cnt <= ni && (hsize_t)cnt <= np, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s has nz = %" PetscInt_FMT " triplets but p, i, x hold %llu, %llu, %llu", file, name, nz, (unsigned long long)np, (unsigned long long)ni, (unsigned long long)nx);
  }
  for (PetscInt e = 0; e < cnt; e++) {
    const long long r = nz >= 0 ? ix[e] : -1, c = nz >= 0 ? p[e] : -1, j = nz >= 0 ? 0 : ix[e];
    if (nz >= 0) PetscCheck(r >= 0 && r < m && c >= 0 && c < n, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s entry %" PetscInt_FMT " at (%lld, %lld) outside %" PetscInt_FMT " x %" PetscInt_FMT, file, name, e, r, c, m, n);
    else PetscCheck(j >= 0 && j < (nz == -2 ? n : m), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s/i[%" PetscInt_FMT "] = %lld outside [0, %" PetscInt_FMT ")", file, name, e, j, nz == -2 ? n : m);
    PetscCheck(PetscAbsReal(x[e]) <= MBC_FCLIB_MAX_ABS, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s/x[%" PetscInt_FMT "] = %g is not finite or beyond %g", file, name, e, x[e], MBC_FCLIB_MAX_ABS);
  }
  /* W and M have a nonzero diagonal, H a nonzero normal column per contact, and H as many rows as
     M (mexp): a size far beyond the entries is a corrupt size field that would be allocated */
  if (mexp >= 0) PetscCheck(m == mexp, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s has %" PetscInt_FMT " rows, expected %" PetscInt_FMT, file, name, m, mexp);
  PetscCheck((mexp >= 0 || m <= 3 * PetscMax(cnt, 1)) && n <= 3 * PetscMax(cnt, 1), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: matrix %s is %" PetscInt_FMT " x %" PetscInt_FMT " but holds %" PetscInt_FMT " entries (more than two thirds of its %s empty)", file, name, m, n, cnt, n > 3 * PetscMax(cnt, 1) ? "columns" : "rows");
  PetscCall(PetscMalloc2(cnt, &row, cnt, &col));
  PetscCall(PetscCalloc1(m, &nnz));
  for (PetscInt k = 0, e = 0; nz < 0 && k < nouter; k++)
    for (long long j = p[k]; j < p[k + 1]; j++, e++) {
      row[e] = nz == -2 ? k : (PetscInt)ix[j];
      col[e] = nz == -2 ? (PetscInt)ix[j] : k;
    }
  for (PetscInt e = 0; nz >= 0 && e < cnt; e++) {
    row[e] = (PetscInt)ix[e];
    col[e] = (PetscInt)p[e];
  }
  for (PetscInt e = 0; e < cnt; e++) nnz[row[e]]++;
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
  for (PetscInt i = 0; i < n; i++) PetscCheck(PetscAbsScalar(a[i]) <= MBC_FCLIB_MAX_ABS, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: %s[%" PetscInt_FMT "] = %g is not finite or beyond %g", file, path, i, (double)PetscRealPart(a[i]), MBC_FCLIB_MAX_ABS);
  PetscCall(VecRestoreArray(*v, &a));
  PetscFunctionReturn(0);
}

/* Every contact's normal entry W_nn must be positive: W = H^T M^-1 H is positive semidefinite and
   W_nn = 0 makes the normal reaction free (the PGS runs to its iteration limit). */
static PetscErrorCode CheckDelassus(const char *file, const char *what, MBCFrictionProblem *fp)
{
  PetscFunctionBegin;
  for (PetscInt i = 0; i < fp->nc; i++) {
    PetscScalar wnn;
    PetscCall(MatGetValue(fp->W, fp->off[i], fp->off[i], &wnn));
    PetscCheck(PetscRealPart(wnn) > 0 && !PetscIsInfOrNanScalar(wnn), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: contact %" PetscInt_FMT " has W_nn = %g%s; a Delassus operator has a positive normal diagonal", file, i, (double)PetscRealPart(wnn), what);
  }
  PetscFunctionReturn(0);
}

/* A global problem M v = H r + f, u = H^T v + w condensed to u = W r + q:
   W = H^T M^-1 H, q = H^T M^-1 f + w (one LU of M by MUMPS, one multi-right-hand-side solve). */
static PetscErrorCode CondenseGlobal(hid_t g, const char *file, MBCFrictionProblem *fp)
{
  Mat            M, H, Hd, X, F, W;
  Vec            f, w, y;
  IS             rperm, cperm;
  MatFactorInfo  info;
  MatFactorError ferr;
  PetscInt       m, n, mm, nm;

  PetscFunctionBegin;
  PetscCall(ReadMatrix(g, file, "M", -1, &M));
  PetscCall(MatGetSize(M, &mm, &nm));
  PetscCall(ReadMatrix(g, file, "H", mm, &H));
  PetscCall(MatGetSize(H, &m, &n));
  PetscCheck(mm == nm, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: M is %" PetscInt_FMT " x %" PetscInt_FMT ", not square", file, mm, nm);
  PetscCheck(m == mm, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: H has %" PetscInt_FMT " rows but M is %" PetscInt_FMT " x %" PetscInt_FMT, file, m, mm, mm);
  PetscCheck(n % 3 == 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: H has %" PetscInt_FMT " columns, not 3 per contact", file, n);
  /* H becomes dense below (m x n doubles) */
  PetscCheck((double)m * (double)n <= 2e8, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: H is %" PetscInt_FMT " x %" PetscInt_FMT ", too large for the dense condensation (%.3g GB)", file, m, n, 8e-9 * m * n);
  for (PetscInt r = 0; r < mm; r++) { /* a zero row of M makes it singular: say so before MUMPS does, with a number */
    PetscInt           ncols;
    const PetscScalar *vals;
    PetscBool          nonzero = PETSC_FALSE;
    PetscCall(MatGetRow(M, r, &ncols, NULL, &vals));
    for (PetscInt k = 0; k < ncols; k++) nonzero = (PetscBool)(nonzero || vals[k] != 0);
    PetscCall(MatRestoreRow(M, r, &ncols, NULL, &vals));
    PetscCheck(nonzero, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: row %" PetscInt_FMT " of the mass matrix M is zero: M is singular", file, r);
  }
  fp->nc = n / 3;
  PetscCall(MBCFrictionProblemSetBlocks(fp, NULL));
  PetscCall(ReadVector(g, file, "vectors/f", m, &f));
  PetscCall(ReadVector(g, file, "vectors/w", n, &w));
  PetscCall(MatGetFactor(M, MATSOLVERMUMPS, MAT_FACTOR_LU, &F));
  PetscCall(MatGetOrdering(M, MATORDERINGNATURAL, &rperm, &cperm));
  PetscCall(MatFactorInfoInitialize(&info));
  PetscCall(MatLUFactorSymbolic(F, M, rperm, cperm, &info));
  PetscCall(MatLUFactorNumeric(F, M, &info));
  PetscCall(MatFactorGetError(F, &ferr));
  PetscCheck(!ferr, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: the LU factorisation of the mass matrix M failed (%s): M is singular", file, ferr == MAT_FACTOR_NUMERIC_ZEROPIVOT ? "zero pivot" : "numerical failure");
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
  {
    PetscReal nq;
    PetscCall(VecNorm(fp->q, NORM_INFINITY, &nq));
    PetscCheck(nq <= MBC_FCLIB_MAX_ABS, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: q = H^T M^-1 f + w has an entry %g (not finite or beyond %g): M is (nearly) singular or f, w too large", file, (double)nq, MBC_FCLIB_MAX_ABS);
  }
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
  PetscCall(CheckDelassus(file, " after condensation (H^T M^-1 H)", fp));
  PetscFunctionReturn(0);
}

static PetscErrorCode FclibReadGroup(hid_t h5, const char file[], MBCFrictionProblem *fp, PetscBool global)
{
  hid_t    g;
  hsize_t  nmu;
  PetscInt n, nw;

  PetscFunctionBegin;
  g = H5Gopen2(h5, global ? "fclib_global" : "fclib_local", H5P_DEFAULT);
  PetscCheck(g >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: /%s is not a group", file, global ? "fclib_global" : "fclib_local");
  if (H5Lexists(g, "spacedim", H5P_DEFAULT) > 0) {
    PetscInt dim;
    PetscCall(H5ReadInt1(g, file, "spacedim", &dim));
    PetscCheck(dim == 3, PETSC_COMM_SELF, PETSC_ERR_SUP, "FCLIB file %s: spacedim %" PetscInt_FMT "; mbcontact solves 3D problems", file, dim);
  }
  if (global) PetscCall(CondenseGlobal(g, file, fp));
  else {
    PetscCall(ReadMatrix(g, file, "W", -1, &fp->W));
    PetscCall(MatGetSize(fp->W, &n, &nw));
    PetscCheck(n == nw, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: W is %" PetscInt_FMT " x %" PetscInt_FMT ", not square", file, n, nw);
    PetscCheck(n % 3 == 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: W has %" PetscInt_FMT " rows, not 3 per contact", file, n);
    fp->nc = n / 3;
    PetscCall(MBCFrictionProblemSetBlocks(fp, NULL));
    PetscCall(ReadVector(g, file, "vectors/q", n, &fp->q));
    PetscCall(CheckDelassus(file, "", fp));
  }
  PetscCall(H5ReadArray(g, file, "vectors/mu", H5T_NATIVE_DOUBLE, NULL, &nmu));
  PetscCheck((PetscInt)nmu == fp->nc, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: %llu friction coefficients for %" PetscInt_FMT " contacts", file, (unsigned long long)nmu, fp->nc);
  PetscCall(PetscMalloc1(fp->nc, &fp->mu));
  PetscCall(H5ReadArray(g, file, "vectors/mu", H5T_NATIVE_DOUBLE, fp->mu, &nmu));
  for (PetscInt i = 0; i < fp->nc; i++) PetscCheck(fp->mu[i] >= 0 && !PetscIsInfOrNanReal(fp->mu[i]), PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s: contact %" PetscInt_FMT " has friction coefficient %g", file, i, (double)fp->mu[i]);
  H5Gclose(g);
  PetscFunctionReturn(0);
}

/* Reads an FCLIB local problem, or a global one condensed to local form. */
PetscErrorCode MBCFclibRead(const char file[], MBCFrictionProblem *fp, PetscBool *global)
{
  hid_t          h5;
  PetscBool      exists;
  PetscErrorCode ierr;

  PetscFunctionBegin;
  PetscCall(PetscMemzero(fp, sizeof(*fp)));
  PetscCall(PetscTestFile(file, 'r', &exists));
  PetscCheck(exists, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "FCLIB file %s does not exist or cannot be read", file);
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  PetscCheck(H5Fis_hdf5(file) > 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s is not an HDF5 file", file);
  h5 = H5Fopen(file, H5F_ACC_RDONLY, H5P_DEFAULT);
  PetscCheck(h5 >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot open FCLIB file %s", file);
  *global = (PetscBool)(H5Lexists(h5, "fclib_global", H5P_DEFAULT) > 0);
  if (!*global && H5Lexists(h5, "fclib_local", H5P_DEFAULT) <= 0) {
    H5Fclose(h5);
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "FCLIB file %s has neither /fclib_local nor /fclib_global", file);
  }
  ierr = FclibReadGroup(h5, file, fp, *global); /* the file is closed on its error paths too */
  H5Fclose(h5);
  PetscCall(ierr);
  PetscCall(PetscStrncpy(fp->title, file, sizeof(fp->title)));
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
  if (fp->description[0]) { /* FCLIB's info group (title, description, math_info strings): what the rows mean, where it is not plain Coulomb contact */
    const char *names[3] = {"title", "description", "math_info"}, *text[3] = {fp->title, fp->description, "u = W r + q, r in the Coulomb cones |r_t| <= mu r_n"};
    hid_t       gi       = H5Gcreate2(g, "info", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    for (int k = 0; k < 3; k++) {
      hid_t type = H5Tcopy(H5T_C_S1), space = H5Screate(H5S_SCALAR), ds;
      H5Tset_size(type, strlen(text[k]) + 1);
      ds = H5Dcreate2(gi, names[k], type, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
      PetscCheck(ds >= 0 && H5Dwrite(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, text[k]) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot write fclib_local/info/%s", names[k]);
      H5Dclose(ds);
      H5Sclose(space);
      H5Tclose(type);
    }
    H5Gclose(gi);
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
