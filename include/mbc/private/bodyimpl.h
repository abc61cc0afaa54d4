/* Private: one contact body, a PETSc subdomain. */
#pragma once

#include <mbc/private/sceneimpl.h>

typedef struct _MBCBodyOps *MBCBodyOps;
struct _MBCBodyOps {
  PetscErrorCode (*view)(MBCBody, PetscViewer);
};

/* The element of a body's cells: tet4 bodies have tet4; hex bodies hex8, hex8i (incompatible
   modes) or hex8b (B-bar, mean dilatation), chosen by the scene's body key `element` or
   -body_[<name>_]element. */
typedef enum {
  MBC_ELEMENT_TET4,
  MBC_ELEMENT_HEX8,
  MBC_ELEMENT_HEX8I,
  MBC_ELEMENT_HEX8B,
  MBC_ELEMENT_TET10, /* a body of tet10 cells */
  MBC_ELEMENT_MIXED, /* tets, prisms and pyramids (with hexes: the hex variant's name) */
  MBC_ELEMENT_RIGID  /* a rigid body: no element */
} MBCElementType;
PETSC_EXTERN const char *const MBCElementTypes[];

/* The type of a cell (bodylayout.c), which the count of its nodes also tells (element.h). */
typedef enum {
  MBC_CELL_TET4,
  MBC_CELL_HEX8,
  MBC_CELL_WEDGE6,
  MBC_CELL_PYR5,
  MBC_CELL_TET10,
  MBC_CELL_TRI3, /* a rigid surface's */
  MBC_CELL_QUAD4
} MBCCellType;
PETSC_EXTERN const char *const MBCCellTypes[];

#define MBC_MAX_CUTS 11 /* dt / 1024 */

/* The coefficients of one step of h: Newmark's a0..a7, generalized-alpha's am, af, cf = af / (1 - af)
   and the mass's coefficient aM = a0 (1 - am) / (1 - af) in the step's operator K + aM M + a1 C. */
typedef struct {
  PetscReal h, a0, a1, a2, a3, a4, a5, a6, a7, am, af, cf, aM;
} MBCTimeCoefficients;

struct _n_MBCBody {
  PETSCHEADER(struct _MBCBodyOps);
  char        name[MBC_NAME_LEN];
  PetscInt    index;      /* position in the scene */
  MPI_Comm    comm;       /* the body's sub-communicator of the job's */
  MBCScene    scene;      /* a reference */
  MBCBodyDesc desc;
  MBCElementType element;

  DM      dm;             /* displacement field, Lagrange P1/Q1 */
  DM      dmStress;       /* cellwise stress, 6 components (xx yy zz xy yz xz) */
  PetscInt *vnum, *cnum;  /* scene index (the order mbcontact-prep wrote) of each local vertex and cell */
  PetscInt *cellvoff, *cellv; /* each local cell's nodes (points) in its kernel's order, cellv[cellvoff[c]..]: kept
                                 because a closure looks up every point's cell type (MBCBodyCellVertices) */
  PetscInt *celltype;     /* each local cell's MBCCellType */
  PetscInt *enode;        /* tet10: per local edge the scene index of its midside node (NULL otherwise) */
  PetscReal *ecoord;      /* and its position, 3 each */
  PetscBool surface;      /* a rigid surface: a 2D mesh, its cells are its faces */
  void     *nodemap;      /* scene node -> local point (MBCBodyNodePoint), built on first use */
  Vec       Trig[6];      /* a rigid body (bodyrigidbody.c): u = T q, T's six columns */
  PetscReal TtTinv[36], Mr[36]; /* (T^T T)^-1 and its mass about the reference point */
  PetscReal lambda, mu;   /* Lamé constants */

  Mat K, M;               /* unconstrained stiffness and mass (lumped: diagonal), M with the reservoir's added mass */
  Mat Cb;                 /* Lysmer-Kuhlemeyer dashpots on the absorbing surfaces (nodal 3 x 3 blocks; NULL: none), part of C */
  Mat Cin;                /* their input weights: 2 (incident) or 1 (outcrop) times the dashpots of the input surfaces (NULL: none) */
  PetscReal aC;           /* coefficient of Cb in A: Newmark's a1 while the Newmark operator is factored (BodyUseLevel), else 0 */
  PetscBool held;         /* the absorbing surfaces are held (static states): bc_rows is the held set */
  PetscInt  nbc_free, *bc_rows_free, *bc_entry_free; /* the Dirichlet set alone (dynamic) */
  PetscInt  nbc_held, *bc_rows_held, *bc_entry_held; /* and with the absorbing surfaces' rows (entry -1: value 0) */
  Vec       fhold;        /* the reactions the absorbing surfaces carried when released: a constant load */
  Vec envelope;           /* per cell (stress layout): the largest principal stress so far [0] and its time [1] (output field envelope) */
  PetscReal cM, cK;       /* damping C = cM M + cK K (never formed) */
  Mat Kbc, Mbc;           /* K's and M's prescribed rows bc_rows (MBCBodyPrescribedRowsForce; NULL until used) */
  const PetscInt *bcrows_of; /* the bc_rows they were taken for */
  Mat A;                  /* operator factored by ksp: K or Newmark's K + a0 M + a1 C, constrained rows/cols zeroed */
  KSP ksp;
  Mat Ainv;               /* the generalised inverse as an operator (MBCBodyGetInverse) */
  Vec fheld;              /* its work: a right side with the held rows zeroed */
  KSP kspcut[MBC_MAX_CUTS]; /* dynamic: the factor of each step size dt / 2^level used (solver.c) */
  Mat Acut[MBC_MAX_CUTS];
  PetscReal a0, a1;       /* coefficients of A = aK K + aM M */
  PetscReal aK, aM;
  PetscReal stab;         /* static: A = K + stab diag(K), a spring to the last iterate */
  PetscReal memory_mb;    /* -mbc_memory_mb: what this rank may hold; a factor MUMPS estimates beyond goes out of core (0: no check) */
  PetscReal wext, wdamp;  /* external work and damping dissipation so far (dynamic) */

  PetscInt  stage;        /* the analysis stage under way: loads of later stages do not act yet */
  PetscInt  nloads;       /* scene loads acting on this body */
  PetscInt *load_index;   /* index of each into the scene's loads */
  Vec      *load;         /* assembled load vector of each, for a unit time factor */

  PetscInt   nbc;         /* constrained DOFs owned by this rank */
  PetscInt  *bc_rows;     /* their global rows, sorted, unique */
  PetscInt  *bc_entry;    /* for each, the dirichlet entry that prescribes it (last one wins) */
  PetscBool  bc_component[3]; /* some DOF of this component is constrained on some rank */
  /* static analysis of a body its supports leave free (bodyrigid.c) */
  PetscInt   nrigid;      /* free rigid-body modes (0 to 6) */
  Vec       *rigid;       /* those modes, orthonormal, 0 on prescribed DOFs */
  PetscInt   nfix, *fix_rows; /* DOFs held at 0 by the generalised inverse K^+ (owned, sorted) */
  PetscReal *erigid;      /* per mode: -R^T (F - K u), the right side of the equilibrium G lambda = e */
  PetscReal *frigid;      /* per mode: R^T F, the load it carries (the scale of e) */
  PetscReal  erigid_round; /* what rounding leaves in e: eps |K|_inf |u|_inf max_j |R_j|_1 */
  PetscReal  fres[6];     /* the resultant of the load F and its moment about the origin (static, this step) */

  Vec u, v, a;            /* displacement, velocity, acceleration */
  Vec u0, v0;             /* the initial state set from the API (MBCBodySetInitialState; NULL: the scene's) */
  Vec du, rhs, f, fold, g, work, work2;
  Vec ustart;             /* static: u where a load step that may be cut began */
};

PETSC_INTERN PetscErrorCode MBCBodyCreate(MPI_Comm, MBCScene, PetscInt, const char[], MBCBody *);
PETSC_INTERN PetscErrorCode MBCBodySetUp(MBCBody, PetscBool, MBCMassType);
PETSC_INTERN PetscErrorCode MBCBodyDestroy(MBCBody *);
PETSC_INTERN PetscErrorCode MBCBodyAssembleLoads(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodyAssembleHydrostatic(MBCBody, MBCLoadDesc *, Vec);
PETSC_INTERN PetscErrorCode MBCBodyLoadResultant(MBCBody, Vec, PetscReal[6]);
PETSC_INTERN PetscErrorCode MBCBodyAssembleElasticity(MBCBody, Mat, Mat);
PETSC_INTERN PetscErrorCode MBCBodyAssembleVolumeLoad(MBCBody, const PetscReal[3], Vec);
PETSC_INTERN PetscErrorCode MBCBodyCreateOperator(MBCBody, Mat *);
PETSC_INTERN PetscErrorCode MBCBodyCellVertices(MBCBody, PetscInt, const PetscScalar[], PetscReal[], PetscInt[], PetscInt *);
/* bodylayout.c: the DOF layout, the cells' and faces' nodes */
PETSC_INTERN PetscErrorCode MBCBodyLayoutSetUp(MBCBody);
PETSC_INTERN PetscInt       MBCBodyPointNode(MBCBody, PetscInt);
PETSC_INTERN PetscErrorCode MBCBodyPointCoordinates(MBCBody, PetscInt, const PetscScalar[], PetscReal[3]);
PETSC_INTERN MBCCellType    MBCBodyCellType(MBCBody, PetscInt);
PETSC_INTERN PetscErrorCode MBCBodyFaceCorners(MBCBody, PetscInt, const PetscScalar[], const char[], PetscInt[4], PetscReal[4][3], PetscInt *, PetscReal[3]);
PETSC_INTERN PetscErrorCode MBCBodyFaceNodes(MBCBody, PetscInt, const PetscScalar[], PetscInt[6], PetscReal[6][3], PetscInt *, PetscInt *);
PETSC_INTERN PetscErrorCode MBCBodyNodePoint(MBCBody, PetscInt, PetscInt *);
PETSC_INTERN PetscErrorCode MBCBodyLayoutDestroy(MBCBody);
/* bodyfaceload.c: pressure and traction on a surface; a face's shape functions and quadrature */
PETSC_INTERN PetscErrorCode MBCBodyAssembleFaceLoad(MBCBody, MBCLoadDesc *, Vec);
typedef PetscErrorCode (*MBCFaceForceFn)(MBCBody, PetscInt, const PetscScalar[], void *, PetscInt[6], PetscReal[6][3], PetscInt *);
PETSC_INTERN PetscErrorCode MBCBodyAssembleFaces(MBCBody, PetscInt, MBCFaceForceFn, void *, Vec);
PETSC_INTERN void           MBCFaceShape(PetscInt, PetscReal, PetscReal, PetscReal[6], PetscReal[6][2]);
PETSC_INTERN void           MBCFaceMap(PetscInt, const PetscReal[6][3], PetscReal, PetscReal, PetscReal[6], PetscReal[3], PetscReal[3], PetscReal[3]);
PETSC_INTERN PetscInt       MBCFaceQuadrature(PetscInt, PetscInt, PetscReal *, PetscReal *, PetscReal *);
PETSC_INTERN void           MBCFaceIntegrate(PetscInt, const PetscReal[6][3], PetscReal (*)(const PetscReal[3], void *), void *, const PetscReal[3], PetscReal[6][3]);
PETSC_INTERN PetscErrorCode MBCBodyFactor(MBCBody, PetscReal, PetscReal, KSP *, Mat *, const char[]);
PETSC_INTERN PetscErrorCode MBCBodyExternalForce(MBCBody, PetscReal, PetscBool, Vec);
PETSC_INTERN PetscErrorCode MBCBodyPrescribed(MBCBody, PetscReal, Vec);
PETSC_INTERN PetscErrorCode MBCBodyPrescribedIncrement(MBCBody, PetscReal, Vec);
PETSC_INTERN PetscErrorCode MBCBodySetConstrainedRows(MBCBody, Vec, Vec);
PETSC_INTERN PetscErrorCode MBCBodyConstrainedSolve(MBCBody, KSP, PetscReal, PetscReal, Vec, Vec, Vec);
PETSC_INTERN PetscErrorCode MBCBodyGetInverse(MBCBody, Mat *);
PETSC_INTERN PetscErrorCode MBCInverseGetKSP(Mat, KSP *);
PETSC_INTERN PetscErrorCode MBCBodyPrescribedRowsForce(MBCBody, PetscBool, Vec);
PETSC_INTERN PetscErrorCode MBCBodyComputeStress(MBCBody, Vec, Vec);
PETSC_INTERN PetscErrorCode MBCBodyCheckFinite(MBCBody, Vec, const char[], PetscReal);
PETSC_INTERN PetscErrorCode MBCBodyRigidModes(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodyRigidModesDestroy(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodyZeroHeldRows(MBCBody, Vec, Mat);
/* bodyuplift.c: a couple's uplift on its faces */
PETSC_INTERN PetscReal      MBCUpliftPressure(const MBCUpliftDesc *, const PetscReal[], const PetscReal[3]);
PETSC_INTERN PetscErrorCode MBCBodyAssembleUplift(MBCBody, MBCLoadDesc *, const PetscReal[], Vec, PetscReal[4]);
PETSC_INTERN PetscErrorCode MBCBodyUpliftUpdate(MBCBody, const PetscReal[], const PetscInt[], PetscReal[]);
/* seismic loads and boundaries (bodysurface.c, bodyaddedmass.c, bodyabsorbing.c) */
typedef PetscErrorCode (*MBCFaceWeights)(PetscInt, const PetscReal[4][3], void *, PetscReal[4]);
PETSC_INTERN PetscErrorCode MBCBodySurfaceBlocks(MBCBody, PetscInt, MBCFaceWeights, void *, PetscReal, PetscReal, Mat);
PETSC_INTERN PetscErrorCode MBCBodyAddedMass(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodyAbsorbingSetUp(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodyAbsorbingHold(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodyAbsorbingRelease(MBCBody, PetscReal);
PETSC_INTERN PetscErrorCode MBCBodyGroundLoad(MBCBody, MBCLoadDesc *, Vec, PetscBool *);
PETSC_INTERN PetscErrorCode MBCBodyEnvelopeUpdate(MBCBody, PetscReal);
PETSC_INTERN PetscErrorCode MBCBodyGetEnvelope(MBCBody, Vec *);
PETSC_INTERN PetscErrorCode MBCBodyAddDamping(MBCBody, PetscReal, Vec, Vec);
PETSC_INTERN PetscErrorCode MBCBodyNodalBlockMatrix(MBCBody, Mat *);
PETSC_INTERN PetscErrorCode MBCBodyInitialState(MBCBody, PetscBool *, PetscBool *);
PETSC_INTERN PetscErrorCode MBCBodyHasInitialState(MBCBody, PetscBool *);
/* bodyrigidbody.c: a rigid body's six DOFs */
PETSC_INTERN PetscErrorCode MBCBodyRigidSetUp(MBCBody, PetscBool);
PETSC_INTERN PetscErrorCode MBCBodyRigidFactor(MBCBody, PetscReal, PetscReal, KSP *, Mat *);
PETSC_INTERN PetscErrorCode MBCBodyRigidMotion(MBCBody, Vec, PetscReal[6]);
PETSC_INTERN PetscErrorCode MBCBodyRigidPrescribed(MBCBody, PetscReal, Vec, Vec);
PETSC_INTERN PetscErrorCode MBCBodyRigidSolve(MBCBody, KSP, PetscReal, Vec, Vec, Vec);
PETSC_INTERN PetscErrorCode MBCBodyRigidFreeModes(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodyRigidGravity(MBCBody, const PetscReal[3], Vec);
PETSC_INTERN PetscErrorCode MBCBodyRigidDestroy(MBCBody);
/* bodyspring.c: discrete springs and dashpots */
PETSC_INTERN PetscBool      MBCBodyHasSprings(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodySpringPattern(MBCBody, Mat);
PETSC_INTERN PetscErrorCode MBCBodySpringsSetUp(MBCBody, PetscBool);
PETSC_INTERN void           MBCBodySpringHeld(MBCBody, PetscBool[3]);
PETSC_INTERN PetscBool      MBCBodyDamped(MBCBody);
/* bodycreate.c: what other modules read of a body, and the contact's share of its increment */
PETSC_INTERN PetscErrorCode MBCBodyGetComm(MBCBody, MPI_Comm *);
PETSC_INTERN PetscErrorCode MBCBodyGetIndex(MBCBody, PetscInt *);
PETSC_INTERN PetscErrorCode MBCBodyGetElement(MBCBody, MBCElementType *, PetscBool *);
PETSC_INTERN PetscErrorCode MBCBodyGetPrescribedRows(MBCBody, PetscInt *, const PetscInt **);
PETSC_INTERN PetscErrorCode MBCBodyGetPrescribedEntries(MBCBody, const PetscInt **);
PETSC_INTERN PetscErrorCode MBCBodyGetHeldRows(MBCBody, PetscInt *, const PetscInt **);
PETSC_INTERN PetscErrorCode MBCBodyGetRigidModes(MBCBody, PetscInt *, const Vec **);
PETSC_INTERN PetscErrorCode MBCBodyGetRigidEquilibrium(MBCBody, const PetscReal **, const PetscReal **, PetscReal *, const PetscReal **);
PETSC_INTERN PetscErrorCode MBCBodyGetIncrement(MBCBody, Vec *);
PETSC_INTERN PetscErrorCode MBCBodyAddIncrement(MBCBody, Vec);
PETSC_INTERN PetscErrorCode MBCBodyAddRigidIncrement(MBCBody, const PetscReal[]);
PETSC_INTERN PetscErrorCode MBCBodyGetAcceleration(MBCBody, Vec *);
PETSC_INTERN PetscErrorCode MBCBodyGetWork(MBCBody, PetscReal *, PetscReal *);
PETSC_INTERN PetscErrorCode MBCBodySetWork(MBCBody, PetscReal, PetscReal);
PETSC_INTERN PetscErrorCode MBCBodyRestartLoad(MBCBody, PetscReal);
PETSC_INTERN PetscErrorCode MBCBodyGetSceneNumbering(MBCBody, const PetscInt **, const PetscInt **);
PETSC_INTERN PetscErrorCode MBCBodyGetCellNodes(MBCBody, PetscInt, PetscInt *, const PetscInt **, MBCCellType *);
PETSC_INTERN PetscErrorCode MBCBodySceneLoadResultant(MBCBody, PetscInt, PetscReal[6], PetscBool *);
/* bodystep.c: the body's part of a load or time step */
PETSC_INTERN PetscErrorCode MBCBodySetMemoryLimit(MBCBody, PetscReal);
PETSC_INTERN PetscErrorCode MBCBodySetStage(MBCBody, PetscInt);
PETSC_INTERN PetscErrorCode MBCBodyEnergy(MBCBody, PetscReal[4]);
PETSC_INTERN PetscErrorCode MBCBodyStaticBegin(MBCBody, PetscReal, PetscBool *, PetscBool *);
PETSC_INTERN PetscErrorCode MBCBodyStaticFactor(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodyStaticIncrement(MBCBody, PetscReal);
PETSC_INTERN PetscErrorCode MBCBodyStaticUpdate(MBCBody, PetscReal, PetscReal[3]);
PETSC_INTERN PetscErrorCode MBCBodyStepSave(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodyStepRestore(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodyAcceleration(MBCBody, PetscReal, Vec);
PETSC_INTERN PetscErrorCode MBCBodyWorkStart(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodyDynamicInitialState(MBCBody);
PETSC_INTERN PetscErrorCode MBCBodyDynamicStageBegin(MBCBody, PetscBool, PetscReal);
PETSC_INTERN PetscErrorCode MBCBodyUseStepLevel(MBCBody, PetscInt, MBCTimeCoefficients);
PETSC_INTERN PetscErrorCode MBCBodyDynamicIncrement(MBCBody, PetscReal, MBCTimeCoefficients, Vec, PetscReal, Vec);
PETSC_INTERN PetscErrorCode MBCBodyDynamicUpdate(MBCBody, PetscReal, MBCTimeCoefficients);
