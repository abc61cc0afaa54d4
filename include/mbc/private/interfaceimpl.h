/* Private: the contact interface, the multiplier problem between the bodies: per body the contact
   matrix H, the flexibility matrix D = H^T A^-1 H, q, the multipliers, their distribution over
   the ranks and the per-point bookkeeping (src/interface/). */
#pragma once

#include <mbc/private/contactimpl.h>
#include <mbc/private/multiplierimpl.h>
#include <petscsf.h>

#define MBC_PAIR_SIZE 4

typedef enum {
  MBC_CONTACT_SEPARATED = 0,
  MBC_CONTACT_STICK     = 1,
  MBC_CONTACT_SLIP      = 2 /* also a frictionless point in contact */
} MBCContactState;

typedef struct _n_MBCInterface *MBCInterface;

/* -mbc_d_route: how D_b = H_b^T A_b^-1 H_b is had */
typedef enum {
  MBC_D_ROUTE_MULTIRHS = 0, /* dense D_b from multi-right-hand-side solves with the body's factor */
  MBC_D_ROUTE_SCHUR    = 1, /* dense D_b through the Schur complement onto the contact DOFs (bodies on one rank) */
  MBC_D_ROUTE_AUTO     = 2, /* matrix-free where the dense D does not fit, else per body Schur where S^-1 fits, else the solves */
  MBC_D_ROUTE_MATFREE  = 3  /* no D: W a shell, a solve per body per product (interfacematfree.c) */
} MBCDRoute;

struct _n_MBCInterface {
  MPI_Comm    comm;       /* the solver's (world) communicator */
  MBCScene    scene;      /* borrowed: names in messages */
  MBCContact  contact;    /* borrowed: the search's points, frames, weights and gaps */
  PetscInt    nbodies;
  MBCBody    *bodies;     /* borrowed: NULL where this rank is not in the body */
  const PetscMPIInt *body_first_rank, *body_nranks; /* borrowed: each body's ranks, for the rank order */
  MBCAnalysisType analysis; /* static: free bodies' rigid modes enter the problem */

  /* the multiplier problem: points in couple order (search, output) on every rank; the rows of
     W, q, lambda in rank order, each point on a rank of the body holding its master node */
  PetscInt   ncontact;    /* contact points of the last build */
  PetscInt  *coff, *poff; /* ncontact + 1: first multiplier of each point in couple order / in rank order */
  PetscInt  *perm, *order; /* couple order k -> rank order perm[k]; rank order p -> couple order order[p] */
  PetscInt  *kcouple, *kpoint; /* couple order k -> its couple and its index there */
  PetscInt   pfirst, plast; /* this rank's points [pfirst, plast) in rank order */
  Mat       *H;           /* per body: contact matrix, the columns of the multipliers touching it (NULL off the body) */
  PetscInt **bcols, *nbcols; /* per body (every rank): the W rows (rank order) of H's columns */
  Vec       *Hu, *lam;    /* per body: H^T du, lambda, in H's column layout */
  Vec       *Hl, *Xl;     /* per body: H lambda and A^-1 H lambda */
  PetscSF    csf;         /* leaves: the H columns on this rank, body after body; roots: the rows of W */
  PetscScalar *leaf;
  VecScatter gather;      /* all multipliers to every rank (rank order), for the output */
  Vec        gathered;
  PetscReal *rall, *uall; /* couple order, every rank: r (scaled) and u = H^T du of the last solve */
  PetscInt   dblock;      /* -mbc_contact_block: columns of A^-1 H per multi-right-hand-side solve */
  PetscInt   droute;      /* -mbc_d_route: MBCDRoute */
  PetscBool  rows_even;   /* -mbc_contact_rows_even: the points' rows split evenly over the ranks */
  PetscReal  schur_max_mb; /* -mbc_d_schur_max_mb: auto takes the Schur route for a body whose S^-1 (and the inverse's entries asked at once) fit in this */
  PetscReal  dense_max_mb; /* -mbc_d_dense_max_mb: auto takes the matrix-free D where the dense one does not fit in this */
  PetscReal  solves_max;   /* -mbc_d_solves_max: auto takes the matrix-free D where building the dense one takes more solves */
  PetscInt   coarse_points; /* -mbc_d_coarse_points: points per patch of the matrix-free Newton steps' coarse space (0: none) */
  PetscReal  coarse_max_mb; /* -mbc_d_coarse_max_mb: the most W Phi may take (larger patches beyond) */
  Mat       *sinv;        /* per body, -mbc_d_route schur: S^-1 on the contact-surface DOFs sinv_is, for the operator sinv_id in state sinv_state */
  IS        *sinv_is;
  PetscInt  *schur_fits;  /* per body, auto: whether its S^-1 fits in -mbc_d_schur_max_mb (-1: not yet known) */
  PetscObjectId *sinv_id;
  PetscObjectState *sinv_state;
  MBCFrictionProblem fp;  /* D, q, mu of the multiplier problem: this rank's rows */
  MBCMultiplier mult;     /* the multiplier solve (-mbc_multiplier_type) */
  PetscReal  dscale;      /* D is scaled by 1/dscale for the PGS: lambda = r / dscale */
  Vec        lambda, ucontact; /* PGS unknown r (scaled) and u = W r + q */
  Vec        lamprev;     /* lambda_n+1 after the step (physical): carried in the acceleration */
  Vec        lamsave;     /* the warm start, restored when a solve that may fail does */
  PetscReal  theta, carry; /* complementarity on z = theta lambda_n+1 + (1 - theta) lambda_n; carry = (1 - theta) / theta */
  PetscBool  release;     /* dynamic, lambda_n through a_n: the points that leave the set, or were separated, at a rebuild go on as separated points (interfacerelease.c) */
  Vec       *released;    /* per body (its layout, NULL where none): their force in the acceleration, H_old lambda times (-carry)^k */
  PetscInt   npairs_built, *pairs_built; /* MBC_PAIR_SIZE per point when D was built: couple, master, face, hash of the slave nodes */
  PetscInt  *bsoff, *bsnode; /* per point (couple order) at the build: the slave nodes of its constraint, bsnode[bsoff[k]..bsoff[k + 1]) */
  PetscReal *bsw;            /* and their weights */
  PetscReal *frames;      /* (n, t1, t2) of each point when D was built (turned where a tangent is held, interfaceheld.c) */
  PetscInt  *held;        /* per point: bit a set where its direction a (n, t1, t2) is held on both sides: no multiplier, no H column */
  PetscBool  held_warned; /* the master nodes prescribed on one side only were named (first build) */
  PetscReal *slip;        /* per point: (0, t1, t2) components of its tangential relative displacement so far (frictional couples) */
  PetscReal *stepslip;    /* per point: the same since the step began (a static step's equilibrium iterations, a step's cut steps) */
  PetscReal *cutslip;     /* per point, static: stepslip where the load step under way began (a step cut in two: the first half's) */
  PetscReal  stepres, cutres; /* what the step's multiplier solves resolve of stepslip, 2 rtol |q| summed over its (cut) steps (MBCInterfaceStates); stepres where the load step under way began */
  PetscReal **jbreak, **jsave; /* per couple with cohesion (NULL otherwise), per master node: the time its bond broke, PETSC_MAX_REAL while
                                 bonded; saved where a static load step begins (interfacejoint.c) */
  PetscReal **jsoft;      /* per couple with softening_displacement (NULL otherwise), 4 per master node: damage D, D and the slip summed
                             where the step began (the base), this step's slip; interfacejoint.c */
  PetscReal  jtol;        /* -mbc_joint_break_rtol: a bond breaks within this fraction of its apex force (c/mu) A of the cone's boundary */
  PetscInt   jbroke, jsolves; /* the last MBCInterfaceSolve: the bonds it broke and its multiplier solves (the monitor's) */
  PetscReal  jfrac;       /* -mbc_joint_break_fraction: a solve breaks the points within this fraction of the largest excess (1: all beyond the cone) */
  char       fclib_file[PETSC_MAX_PATH_LEN]; /* -mbc_fclib_write: the multiplier problem of step fclib_step */
  PetscInt   fclib_step;

  /* static analysis: free bodies (FETI's natural coarse space G = R^T H) */
  PetscInt   ngrigid, *goff; /* free rigid modes of all bodies; body b's are goff[b].. goff[b+1] */
  PetscScalar *gQ;        /* eigenvectors of G G^T (ng x ng, the k-th at gQ[k ng]) */
  PetscInt   grank, *grange; /* the rank of G and the eigenvectors of its range (NULL when G has full rank) */
  PetscReal *gscale;      /* the scale of each row of the problem's G */
};

PETSC_EXTERN PetscLogEvent MBC_FlexibilityAssemble, MBC_FlexibilityMult, MBC_FlexibilityCoarse;

/* interface.c: the object, the rank order, H and D */
PETSC_INTERN PetscErrorCode MBCInterfaceCreate(MPI_Comm, MBCScene, MBCContact, PetscInt, MBCBody[], const PetscMPIInt[], const PetscMPIInt[], const char[], MBCInterface *);
PETSC_INTERN PetscErrorCode MBCInterfaceSetTimeStepping(MBCInterface, MBCAnalysisType, PetscReal, PetscBool);
PETSC_INTERN PetscErrorCode MBCInterfaceSetBlockSize(MBCInterface, PetscInt);
PETSC_INTERN PetscErrorCode MBCInterfaceSetDRoute(MBCInterface, PetscInt, PetscReal, PetscReal, PetscReal);
PETSC_INTERN PetscErrorCode MBCInterfaceSetRowsEven(MBCInterface, PetscBool);
PETSC_INTERN PetscErrorCode MBCInterfaceSetFclibWrite(MBCInterface, const char[], PetscInt);
PETSC_INTERN PetscErrorCode MBCInterfaceGetPairs(MBCInterface, PetscInt *, PetscInt **, PetscBool *);
PETSC_INTERN PetscErrorCode MBCInterfaceSetUp(MBCInterface, PetscInt, PetscInt[]);
PETSC_INTERN PetscErrorCode MBCInterfaceRebuildD(MBCInterface);
PETSC_INTERN PetscErrorCode MBCInterfaceGetState(MBCInterface, PetscInt *, PetscInt *, PetscReal[], const PetscReal **, const PetscReal **, const PetscInt **);
PETSC_INTERN PetscErrorCode MBCInterfaceSetState(MBCInterface, const PetscReal[], const PetscReal[], const PetscReal[]);
PETSC_INTERN PetscErrorCode MBCInterfaceGetSolveState(MBCInterface, PetscReal[], PetscBool *);
PETSC_INTERN PetscErrorCode MBCInterfaceSetSolveState(MBCInterface, const PetscReal[]);
PETSC_INTERN PetscErrorCode MBCInterfaceGetSize(MBCInterface, PetscInt *, PetscInt *);
PETSC_INTERN PetscErrorCode MBCInterfaceGetMultiplier(MBCInterface, MBCMultiplier *);
PETSC_INTERN PetscErrorCode MBCInterfaceGetMultipliers(MBCInterface, Vec *);
PETSC_INTERN PetscErrorCode MBCInterfaceMultipliersToBodies(MBCInterface);
PETSC_INTERN PetscErrorCode MBCInterfaceBodyForce(MBCInterface, PetscInt, Vec);
PETSC_INTERN PetscErrorCode MBCInterfaceDestroy(MBCInterface *);
PETSC_INTERN PetscBool      MBCInterfacePointTouches(const MBCCouple *, PetscInt, PetscInt);
PETSC_INTERN PetscErrorCode MBCInterfaceToBodies(MBCInterface, Vec);
PETSC_INTERN PetscErrorCode MBCInterfaceScatterToBodies(MBCInterface, Vec, Vec[]);
PETSC_INTERN PetscErrorCode MBCInterfaceGatherFromBodies(MBCInterface, Vec[], Vec);
PETSC_INTERN PetscErrorCode MBCInterfaceBodySolveColumns(MBCInterface, PetscInt, PetscInt, const PetscInt[], Mat *, Mat *);
/* interfacerelease.c: the points that leave the contact set in a dynamic step */
PETSC_INTERN PetscErrorCode MBCInterfaceRelease(MBCInterface, PetscInt, const PetscInt[], PetscReal[]);
PETSC_INTERN PetscErrorCode MBCInterfaceGetReleasedStepForce(MBCInterface, PetscInt, PetscReal *, Vec *);
PETSC_INTERN PetscErrorCode MBCInterfaceReleasedStep(MBCInterface);
PETSC_INTERN PetscErrorCode MBCInterfaceGetReleasedForce(MBCInterface, PetscInt, Vec *);
PETSC_INTERN PetscErrorCode MBCInterfaceReleasedClear(MBCInterface);
/* interfacematfree.c: the matrix-free D */
PETSC_INTERN PetscErrorCode MBCInterfaceBuildDShell(MBCInterface, PetscInt, PetscInt);
PETSC_INTERN PetscErrorCode MBCInterfaceBuildCoarse(MBCInterface, PetscInt);
PETSC_INTERN PetscErrorCode MBCInterfaceSetCoarse(MBCInterface, PetscInt, PetscReal);
PETSC_INTERN PetscErrorCode MBCInterfaceFromBodies(MBCInterface, Vec);
PETSC_INTERN PetscErrorCode MBCInterfaceGapRate(MBCInterface, Vec);
PETSC_INTERN PetscReal      MBCInterfaceStartGap(MBCInterface, PetscInt);
PETSC_INTERN PetscErrorCode MBCInterfaceGather(MBCInterface, Vec, PetscReal[]);
/* interfacerigid.c: free bodies in a static analysis */
PETSC_INTERN PetscErrorCode MBCInterfaceRigidModes(MBCInterface);
PETSC_INTERN PetscErrorCode MBCInterfaceRigidRHS(MBCInterface, PetscInt, PetscReal);
PETSC_INTERN PetscErrorCode MBCInterfaceRigidMotion(MBCInterface);
/* interfaceheld.c: contact points on prescribed nodes */
PETSC_INTERN PetscErrorCode MBCInterfaceHeldDirections(MBCInterface);
/* interfacejoint.c: bonded couples (cohesion, tensile strength, brittle break) */
PETSC_INTERN PetscBool      MBCInterfaceHasJoints(MBCInterface);
PETSC_INTERN PetscInt       MBCInterfaceJointPoint(MBCInterface, PetscInt, PetscInt, PetscReal *);
PETSC_INTERN PetscReal      MBCInterfaceJointMu(MBCInterface, PetscInt);
PETSC_INTERN PetscInt       MBCInterfaceJointBonded(MBCInterface);
PETSC_INTERN PetscErrorCode MBCInterfaceJointProblem(MBCInterface, Vec);
PETSC_INTERN PetscErrorCode MBCInterfaceJointBreak(MBCInterface, PetscReal, PetscInt *);
PETSC_INTERN PetscErrorCode MBCInterfaceJointSave(MBCInterface, PetscBool);
PETSC_INTERN PetscErrorCode MBCInterfaceJointUnbreak(MBCInterface, PetscReal);
PETSC_INTERN PetscBool      MBCInterfaceHasSoftening(MBCInterface);
PETSC_INTERN PetscReal      MBCInterfaceJointDamage(MBCInterface, PetscInt, PetscInt);
PETSC_INTERN PetscErrorCode MBCInterfaceJointSoften(MBCInterface, PetscReal, PetscInt *, PetscReal *);
PETSC_INTERN PetscErrorCode MBCInterfaceJointCommit(MBCInterface, PetscBool);
PETSC_INTERN PetscErrorCode MBCInterfaceJointGetState(MBCInterface, PetscInt *, PetscReal[]);
PETSC_INTERN PetscErrorCode MBCInterfaceJointSetState(MBCInterface, PetscInt, const PetscReal[]);
PETSC_INTERN PetscErrorCode MBCInterfaceSetJointBreak(MBCInterface, PetscReal, PetscReal);
PETSC_INTERN PetscErrorCode MBCInterfaceJointDestroy(MBCInterface);
/* interfacesolve.c: the multipliers of a step */
PETSC_INTERN PetscErrorCode MBCInterfaceSolve(MBCInterface, PetscInt, PetscReal, PetscBool, PetscBool *);
PETSC_INTERN PetscErrorCode MBCInterfaceStepBegin(MBCInterface);
PETSC_INTERN PetscErrorCode MBCInterfaceLoadStepBegin(MBCInterface);
PETSC_INTERN PetscErrorCode MBCInterfaceStepAbandon(MBCInterface);
PETSC_INTERN PetscErrorCode MBCInterfaceStates(MBCInterface, PetscInt[3], PetscInt[], PetscReal[]);
PETSC_INTERN void           MBCInterfaceContactWork(MBCInterface, PetscReal *, PetscReal *);
