/* Private: contact-face couples and their search (docs/contact-search.md). */
#pragma once

#include <mbc/private/bodyimpl.h>

#define MBC_MAX_FACE_NODES 4
#define MBC_SEARCH_CANDIDATES 8 /* slave nodes tried per master node, nearest first */

/* One side of a couple: nodes and faces gathered from all bodies and ranks, in canonical
   order (body, then reference coordinates), so results do not depend on the rank count. */
typedef struct {
  PetscInt   nnodes, nfaces;
  PetscInt  *nbody;         /* per node: body index */
  PetscInt  *nrow;          /* per node: first global row of its DOFs in the body's Vec */
  PetscReal *x0, *x;        /* per node: reference and current coordinates (3 each) */
  PetscReal *nnormal;       /* per node: averaged unit normal */
  PetscInt  *fnv, *fnode;   /* per face: vertex count and node indices (MBC_MAX_FACE_NODES each), counter-clockwise seen from outside */
  PetscInt  *fbody;
  PetscReal *fnormal;       /* per face: unit outward normal (Newell: area-weighted, warped quads too) */
  PetscReal *fcenter;
  PetscInt  *n2foff, *n2f;  /* node -> faces (CSR) */
} MBCSurface;

typedef struct {
  PetscInt  master;                          /* master node */
  PetscInt  ncand, cand[MBC_SEARCH_CANDIDATES]; /* slave nodes within h, nearest first (cand[0]: partner) */
  PetscReal distance;                        /* to the partner */
} MBCTestPair;

typedef struct {
  PetscInt  master, face, nv;
  PetscReal w[MBC_MAX_FACE_NODES], p[3], n[3], t1[3], t2[3], gap;
} MBCContactPoint;

typedef struct {
  PetscInt   k;
  PetscReal  mu;
  MBCSurface master, slave;
  PetscReal  h, margin, lo[3];
  PetscInt   npairs, ntests;
  MBCTestPair *pairs;
  PetscInt   npoints;
  MBCContactPoint *points;
} MBCCouple;

typedef struct _n_MBCContact *MBCContact;
struct _n_MBCContact {
  MPI_Comm   comm;
  MBCScene   scene;         /* borrowed */
  PetscInt   ncouples;
  MBCCouple *couples;
  PetscReal  cell_factor, margin;   /* margin <= 0: one cell edge */
  PetscBool  view;
  char       dump[PETSC_MAX_PATH_LEN];
  PetscInt   nsearches;     /* global searches so far */
  Vec       *usearch;       /* per body: displacement at the last global search (NULL off the body) */
};

PETSC_EXTERN PetscLogEvent MBC_ContactGather, MBC_GlobalSearch, MBC_LocalSearch;

PETSC_INTERN PetscErrorCode MBCContactCreate(MPI_Comm, MBCScene, MBCContact *);
PETSC_INTERN PetscErrorCode MBCContactSetFromOptions(MBCContact);
PETSC_INTERN PetscErrorCode MBCContactUpdate(MBCContact, PetscInt, MBCBody[], PetscBool, PetscBool *);
PETSC_INTERN PetscErrorCode MBCContactView(MBCContact, PetscViewer);
PETSC_INTERN PetscErrorCode MBCContactDump(MBCContact);
PETSC_INTERN PetscErrorCode MBCContactDestroy(MBCContact *);

/* the search on gathered surfaces (no MPI): contactsearch.c */
PETSC_EXTERN PetscErrorCode MBCSurfaceSetUp(MBCSurface *);
PETSC_EXTERN PetscErrorCode MBCSurfaceReset(MBCSurface *);
PETSC_EXTERN PetscErrorCode MBCCoupleGlobalSearch(MBCCouple *, PetscReal, PetscReal);
PETSC_EXTERN PetscErrorCode MBCCoupleLocalSearch(MBCCouple *);
