/* HDF5 C API helpers: the serial dataset writer of FCLIB, and the collective ones of the result
   file, which every rank of the solver's communicator opens with the MPI-IO driver. */
#include <mbc/private/h5util.h>
#include <stdlib.h>

/* Dataset name under loc: n entries of ncomp components (1D when ncomp is 1). */
PetscErrorCode MBCH5WriteArray(hid_t loc, const char name[], hid_t type, PetscInt n, PetscInt ncomp, const void *buf)
{
  hsize_t dims[2] = {(hsize_t)n, (hsize_t)ncomp};
  hid_t   sp      = H5Screate_simple(ncomp > 1 ? 2 : 1, dims, NULL), d;

  PetscFunctionBegin;
  d = H5Dcreate2(loc, name, type, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  PetscCheck(d >= 0 && H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot write HDF5 dataset %s", name);
  H5Dclose(d);
  H5Sclose(sp);
  PetscFunctionReturn(0);
}

/* "FILE:/path/name" of an object to be made under loc, for error messages. */
static void H5Where(hid_t loc, const char name[], char *where, size_t len)
{
  char file[PETSC_MAX_PATH_LEN] = "?", path[PETSC_MAX_PATH_LEN] = "";

  H5Fget_name(loc, file, sizeof(file));
  H5Iget_name(loc, path, sizeof(path));
  snprintf(where, len, "%s:%s%s%s", file, path, strcmp(path, "/") ? "/" : "", name);
}

/* Open MPI 4.1's MPI-IO (ompio, through its sharedfp component) aborts with "buffer overflow
   detected" on a file path of 246 characters or more, before HDF5 returns: refuse it with a
   message, unless ROMIO or another sharedfp component is chosen. */
PetscErrorCode MBCH5CheckPathLength(const char path[], const char what[])
{
  const char *io = getenv("OMPI_MCA_io"), *sharedfp = getenv("OMPI_MCA_sharedfp");
  size_t      len;

  PetscFunctionBegin;
  PetscCall(PetscStrlen(path, &len));
  PetscCheck(len < 246 || (io && strstr(io, "romio")) || sharedfp, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "The %s %s is %zu characters long: Open MPI's MPI-IO (ompio) aborts on paths of 246 characters or more; use a shorter path, or set OMPI_MCA_io=romio321", what, path, len);
  PetscFunctionReturn(0);
}

/* A new file (truncating an old one) on all ranks of comm, with the MPI-IO driver and collective
   metadata operations. HDF5's own error stack is silenced: failures are PETSc errors naming the
   file. */
PetscErrorCode MBCH5FileCreate(MPI_Comm comm, const char path[], hid_t *file)
{
  hid_t fapl;

  PetscFunctionBegin;
  PetscCall(MBCH5CheckPathLength(path, "result file"));
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  fapl = H5Pcreate(H5P_FILE_ACCESS);
  PetscCheck(fapl >= 0 && H5Pset_fapl_mpio(fapl, comm, MPI_INFO_NULL) >= 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "Cannot set up parallel HDF5 (MPI-IO) for %s", path);
  PetscCheck(H5Pset_all_coll_metadata_ops(fapl, 1) >= 0 && H5Pset_coll_metadata_write(fapl, 1) >= 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "Cannot set up parallel HDF5 (collective metadata) for %s", path);
  H5Pset_fclose_degree(fapl, H5F_CLOSE_STRONG); /* a close after an error also closes what it left open */
  *file = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, fapl);
  H5Pclose(fapl);
  PetscCheck(*file >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot create the result file %s (does its folder exist, is it writable?)", path);
  PetscFunctionReturn(0);
}

/* Everything written so far to disk, superblock and metadata included, so that the file reads
   back as it is now even if the process is killed before the next flush. Collective. */
PetscErrorCode MBCH5FileFlush(hid_t file)
{
  char name[PETSC_MAX_PATH_LEN] = "?";

  PetscFunctionBegin;
  if (H5Fflush(file, H5F_SCOPE_GLOBAL) < 0) {
    H5Fget_name(file, name, sizeof(name));
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot flush the result file %s (is the disk full, or the file-size limit, ulimit -f, reached?)", name);
  }
  PetscFunctionReturn(0);
}

PetscErrorCode MBCH5FileClose(hid_t *file)
{
  char name[PETSC_MAX_PATH_LEN] = "?";

  PetscFunctionBegin;
  if (*file < 0) PetscFunctionReturn(0);
  H5Fget_name(*file, name, sizeof(name));
  PetscCheck(H5Fclose(*file) >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot close the result file %s (is the disk full?)", name);
  *file = -1;
  PetscFunctionReturn(0);
}

/* Group name under loc; ordered: its links iterate in creation order (h5py, h5ls). */
PetscErrorCode MBCH5GroupCreate(hid_t loc, const char name[], PetscBool ordered, hid_t *group)
{
  hid_t gcpl = H5Pcreate(H5P_GROUP_CREATE);

  PetscFunctionBegin;
  if (ordered) H5Pset_link_creation_order(gcpl, H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED);
  *group = H5Gcreate2(loc, name, H5P_DEFAULT, gcpl, H5P_DEFAULT);
  H5Pclose(gcpl);
  if (*group < 0) {
    char where[2 * PETSC_MAX_PATH_LEN];
    H5Where(loc, name, where, sizeof(where));
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot create the HDF5 group %s", where);
  }
  PetscFunctionReturn(0);
}

PetscErrorCode MBCH5GroupClose(hid_t *group)
{
  PetscFunctionBegin;
  if (*group >= 0) H5Gclose(*group);
  *group = -1;
  PetscFunctionReturn(0);
}

/* Dataset name under loc with nrows rows of ncomp components (1D when ncomp is 1), of which this
   rank writes rows [rstart, rstart + nlocal) from buf (nlocal may be 0: the rank selects none).
   The creation and the write are collective. */
PetscErrorCode MBCH5WriteRows(hid_t loc, const char name[], hid_t type, PetscInt nrows, PetscInt ncomp, PetscInt rstart, PetscInt nlocal, const void *buf)
{
  const int rank     = ncomp > 1 ? 2 : 1;
  hsize_t   dims[2]  = {(hsize_t)nrows, (hsize_t)ncomp};
  hsize_t   start[2] = {(hsize_t)rstart, 0}, count[2] = {(hsize_t)nlocal, (hsize_t)ncomp};
  hsize_t   mdims[2] = {(hsize_t)PetscMax(nlocal, 1), (hsize_t)ncomp};
  hid_t     fsp, msp, dset, dxpl;
  herr_t    err = 0;
  double    dummy = 0;

  PetscFunctionBegin;
  PetscCheck(rstart >= 0 && nlocal >= 0 && rstart + nlocal <= nrows, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Rows [%" PetscInt_FMT ", %" PetscInt_FMT ") of dataset %s outside [0, %" PetscInt_FMT ")", rstart, rstart + nlocal, name, nrows);
  fsp  = H5Screate_simple(rank, dims, NULL);
  dset = H5Dcreate2(loc, name, type, fsp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  if (dset >= 0 && nrows > 0) {
    msp = H5Screate_simple(rank, mdims, NULL);
    if (nlocal) err = H5Sselect_hyperslab(fsp, H5S_SELECT_SET, start, NULL, count, NULL);
    else {
      H5Sselect_none(fsp);
      H5Sselect_none(msp);
    }
    dxpl = H5Pcreate(H5P_DATASET_XFER);
    H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE);
    if (err >= 0) err = H5Dwrite(dset, type, msp, fsp, dxpl, nlocal ? buf : (const void *)&dummy);
    H5Pclose(dxpl);
    H5Sclose(msp);
  }
  H5Sclose(fsp);
  if (dset >= 0) H5Dclose(dset);
  if (dset < 0 || err < 0) {
    char where[2 * PETSC_MAX_PATH_LEN];
    H5Where(loc, name, where, sizeof(where));
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot %s the HDF5 dataset %s (is the disk full, or the file-size limit, ulimit -f, reached?)", dset < 0 ? "create" : "write", where);
  }
  PetscFunctionReturn(0);
}

/* 1D dataset name under loc that grows: made extensible (chunked) by the first call, resized to
   nrows, rows [rstart, rstart + nlocal) of it written by this rank from buf. Collective. */
PetscErrorCode MBCH5WriteRowsGrow(hid_t loc, const char name[], hid_t type, PetscInt nrows, PetscInt rstart, PetscInt nlocal, const void *buf)
{
  hsize_t dims = (hsize_t)nrows, maxdims = H5S_UNLIMITED, chunk = 256, start = (hsize_t)rstart, count = (hsize_t)nlocal, mdims = (hsize_t)PetscMax(nlocal, 1);
  hid_t   fsp, msp, dset, dxpl;
  herr_t  err   = 0;
  double  dummy = 0;

  PetscFunctionBegin;
  PetscCheck(rstart >= 0 && nlocal >= 0 && rstart + nlocal <= nrows, PETSC_COMM_SELF, PETSC_ERR_PLIB, "Rows [%" PetscInt_FMT ", %" PetscInt_FMT ") of dataset %s outside [0, %" PetscInt_FMT ")", rstart, rstart + nlocal, name, nrows);
  if (H5Lexists(loc, name, H5P_DEFAULT) > 0) {
    dset = H5Dopen2(loc, name, H5P_DEFAULT);
    if (dset >= 0) err = H5Dset_extent(dset, &dims);
  } else {
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 1, &chunk);
    fsp  = H5Screate_simple(1, &dims, &maxdims);
    dset = H5Dcreate2(loc, name, type, fsp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    H5Sclose(fsp);
    H5Pclose(dcpl);
  }
  if (dset >= 0 && err >= 0 && nrows > 0) {
    fsp = H5Dget_space(dset);
    msp = H5Screate_simple(1, &mdims, NULL);
    if (nlocal) err = H5Sselect_hyperslab(fsp, H5S_SELECT_SET, &start, NULL, &count, NULL);
    else {
      H5Sselect_none(fsp);
      H5Sselect_none(msp);
    }
    dxpl = H5Pcreate(H5P_DATASET_XFER);
    H5Pset_dxpl_mpio(dxpl, H5FD_MPIO_COLLECTIVE);
    if (err >= 0) err = H5Dwrite(dset, type, msp, fsp, dxpl, nlocal ? buf : (const void *)&dummy);
    H5Pclose(dxpl);
    H5Sclose(msp);
    H5Sclose(fsp);
  }
  if (dset >= 0) H5Dclose(dset);
  if (dset < 0 || err < 0) {
    char where[2 * PETSC_MAX_PATH_LEN];
    H5Where(loc, name, where, sizeof(where));
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot write the HDF5 dataset %s (is the disk full, or the file-size limit, ulimit -f, reached?)", where);
  }
  PetscFunctionReturn(0);
}

/* Attribute name of loc: n values (a scalar when n is 1), the same on every rank; an existing
   one is overwritten (its type and size must be the same). */
PetscErrorCode MBCH5WriteAttribute(hid_t loc, const char name[], hid_t type, PetscInt n, const void *value)
{
  hsize_t dims = (hsize_t)n;
  hid_t   sp   = n == 1 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &dims, NULL), at;
  herr_t  err  = -1;

  PetscFunctionBegin;
  at = H5Aexists(loc, name) > 0 ? H5Aopen(loc, name, H5P_DEFAULT) : H5Acreate2(loc, name, type, sp, H5P_DEFAULT, H5P_DEFAULT); /* an existing one is overwritten */
  if (at >= 0) {
    err = H5Awrite(at, type, value);
    H5Aclose(at);
  }
  H5Sclose(sp);
  if (err < 0) {
    char where[2 * PETSC_MAX_PATH_LEN];
    H5Where(loc, name, where, sizeof(where));
    SETERRQ(PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot write the HDF5 attribute %s", where);
  }
  PetscFunctionReturn(0);
}

/* A fixed-length ASCII string attribute (the scene file's convention, docs/scene-h5.md). */
PetscErrorCode MBCH5WriteAttributeString(hid_t loc, const char name[], const char value[])
{
  hid_t type = H5Tcopy(H5T_C_S1);

  PetscFunctionBegin;
  H5Tset_size(type, PetscMax(strlen(value), 1));
  H5Tset_strpad(type, H5T_STR_NULLPAD);
  PetscCall(MBCH5WriteAttribute(loc, name, type, 1, value));
  H5Tclose(type);
  PetscFunctionReturn(0);
}
