/* Private: small helpers for the files mbcontact writes with the HDF5 C API: on one rank (FCLIB)
   or collectively on all ranks of a communicator (the result file). */
#pragma once

#include <petscsys.h>
#include <hdf5.h>

PETSC_INTERN PetscErrorCode MBCH5CheckPathLength(const char[], const char[]);
PETSC_INTERN PetscErrorCode MBCH5WriteArray(hid_t, const char[], hid_t, PetscInt, PetscInt, const void *);

/* Collective on the file's communicator: every rank calls each one with the same arguments
   (except the rows it writes). */
PETSC_INTERN PetscErrorCode MBCH5FileCreate(MPI_Comm, const char[], hid_t *);
PETSC_INTERN PetscErrorCode MBCH5FileFlush(hid_t);
PETSC_INTERN PetscErrorCode MBCH5FileClose(hid_t *);
PETSC_INTERN PetscErrorCode MBCH5GroupCreate(hid_t, const char[], PetscBool, hid_t *);
PETSC_INTERN PetscErrorCode MBCH5GroupClose(hid_t *);
PETSC_INTERN PetscErrorCode MBCH5WriteRows(hid_t, const char[], hid_t, PetscInt, PetscInt, PetscInt, PetscInt, const void *);
PETSC_INTERN PetscErrorCode MBCH5WriteRowsGrow(hid_t, const char[], hid_t, PetscInt, PetscInt, PetscInt, const void *);
PETSC_INTERN PetscErrorCode MBCH5WriteAttribute(hid_t, const char[], hid_t, PetscInt, const void *);
PETSC_INTERN PetscErrorCode MBCH5WriteAttributeString(hid_t, const char[], const char[]);
