/* Private: small helpers for files mbcontact writes with the HDF5 C API on one rank. */
#pragma once

#include <petscsys.h>
#include <hdf5.h>

PETSC_INTERN PetscErrorCode MBCH5WriteArray(hid_t, const char[], hid_t, PetscInt, PetscInt, const void *);
