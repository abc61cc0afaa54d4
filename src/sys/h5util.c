/* HDF5 C API helpers shared by the FCLIB writer and the contact output. */
#include <mbc/private/h5util.h>

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
