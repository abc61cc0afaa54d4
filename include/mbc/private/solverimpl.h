/* Private: the solver, the bodies of a scene and their time stepping. */
#pragma once

#include <mbc/private/contactimpl.h>
#include <petscsf.h>
#include <mbc/private/multiplierimpl.h>
#include <stdint.h>

typedef struct {
  PetscInt  body;         /* body holding the nearest vertex */
  PetscInt  rank;         /* world rank owning it */
  PetscInt  row;          /* its first global row in the body's displacement Vec (on that rank) */
  PetscReal distance, xv[3];
} MBCPointLocation;

/* One body in the result file (solveroutputbody.c): the rows of its scene-ordered datasets this
   rank writes, and the star forests that bring them there from the distributed mesh. */
typedef struct {
  PetscInt   nv, nc, nvpc;   /* the scene's vertices, cells, vertices per cell */
  PetscInt   vstart, nvrows; /* this rank writes vertex rows [vstart, vstart + nvrows) */
  PetscInt   cstart, ncrows; /* and cell rows [cstart, cstart + ncrows) (0 rows off the body) */
  PetscSF    vsf, csf;       /* values of owned vertices (3 each) and cells (6 each) -> their rows; NULL off the body */
  PetscInt   nvown, *vrow;   /* owned vertices: local row of each in the displacement Vec */
  PetscInt   ncown, *crow;   /* owned cells: local row of each in the stress Vec */
  PetscReal *leaf, *root;    /* work: values of the owned points; this rank's rows (displacement, then stress) */
} MBCBodyOutput;

#define MBC_PAIR_SIZE 4
#define MBC_NENERGY   6 /* kinetic, strain, external work, damping, friction, normal contact */

typedef enum {
  MBC_CONTACT_SEPARATED = 0,
  MBC_CONTACT_STICK     = 1,
  MBC_CONTACT_SLIP      = 2 /* also a frictionless point in contact */
} MBCContactState;

typedef struct _MBCSolverOps *MBCSolverOps;
struct _MBCSolverOps {
  PetscErrorCode (*view)(MBCSolver, PetscViewer);
};

struct _n_MBCSolver {
  PETSCHEADER(struct _MBCSolverOps);
  MPI_Comm  comm;         /* the user's communicator (the header holds PETSc's duplicate) */
  MBCScene  scene;        /* a reference (MBCSolverSetScene) */
  PetscBool setupcalled;
  PetscInt  stage;        /* of the run: 0 before MBCSolverStep's first call, 1 stepping, 2 every step done */
  PetscErrorCode (*usermonitor)(MBCSolver, PetscInt, PetscReal, void *); /* MBCSolverMonitorSet */
  void          *monitorctx;
  PetscErrorCode (*monitordestroy)(void **);

  MBCAnalysisType analysis;
  MBCMassType     mass;
  PetscReal       dt, final_time, beta, gamma;
  PetscInt        nsteps, step;
  PetscReal       time;

  PetscInt  nbodies;
  MBCBody  *bodies;       /* NULL where this rank is not in the body */
  PetscMPIInt *body_first_rank, *body_nranks;
  PetscReal   decomp_cut, decomp_imbalance; /* contact faces between bodies on different ranks; largest rank load / mean */

  /* output */
  char      output[PETSC_MAX_PATH_LEN];
  PetscInt  output_every, noutputs;
  PetscReal *output_times;
  PetscInt *output_npoints; /* contact points written at each output (XDMF) */
  int      *output_cuts;    /* step halvings since the output before (/cuts in the result file) */
  PetscInt  cuts_written;   /* ncuts at the last output */
  char      h5file[PETSC_MAX_PATH_LEN]; /* <output>.h5: every body and the contact points, written collectively */
  int64_t   h5;           /* its hid_t on every rank, -1 when not open */
  MBCBodyOutput *bout;    /* per body, where the file has fields */
  FILE     *points_csv, *energy_csv, *contact_csv;
  MBCPointLocation *points;
  PetscBool monitor, view;

  MBCContact contact;     /* NULL when the scene has no couples */
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
  MBCFrictionProblem fp;  /* D, q, mu of the multiplier problem: this rank's rows */
  MBCMultiplier mult;     /* the multiplier solve (-mbc_multiplier_type) */
  PetscReal  dscale;      /* D is scaled by 1/dscale for the PGS: lambda = r / dscale */
  Vec        lambda, ucontact; /* PGS unknown r (scaled) and u = W r + q */
  Vec        lamprev;     /* lambda_n+1 after the step (physical): carried in the acceleration */
  PetscReal  theta, carry; /* complementarity on z = theta lambda_n+1 + (1 - theta) lambda_n; carry = (1 - theta) / theta */
  PetscInt   npairs_built, *pairs_built; /* MBC_PAIR_SIZE per point when D was built: couple, master, face, hash of the slave nodes */
  PetscReal *frames;      /* (n, t1, t2) of each point when D was built */
  PetscReal *slip;        /* per point: (0, t1, t2) components of its tangential relative displacement so far (frictional couples) */
  PetscReal *stepslip;    /* per point, static: the same since the load step began (its earlier equilibrium iterations) */
  PetscBool  search_only;
  char       fclib_file[PETSC_MAX_PATH_LEN]; /* -mbc_fclib_write: the multiplier problem of step fclib_step */
  PetscInt   fclib_step;

  /* step control: a dynamic step whose contact solve fails, a static load step that does not
     converge, is cut in two, down to dt_min */
  PetscBool  dt_cut, contact_may_fail, contact_failed, force_build;
  PetscReal  dt_min;
  PetscInt   level, ncuts; /* the current step is dt / 2^level; steps cut so far */
  PetscInt   start_level, good_steps, deepest; /* a scene step starts at dt / 2^start_level; steps since without a cut; finest level of this step */
  Vec        lamsave;     /* the warm start, restored when a solve that may fail does */

  /* static analysis: equilibrium iterations, stabilisation of bodies held only by contact */
  PetscInt   ngrigid, *goff; /* free rigid modes of all bodies; body b's are goff[b].. goff[b+1] (static) */
  PetscScalar *gQ;        /* eigenvectors of G G^T (ng x ng, the k-th at gQ[k ng]) */
  PetscInt   grank, *grange; /* the rank of G and the eigenvectors of its range (NULL when G has full rank) */
  PetscReal *gscale;      /* the scale of each row of the problem's G */
  PetscReal  static_stabilize, static_rtol;
  PetscBool  static_stabilized, static_floating; /* some body has the spring, or free rigid modes: iterate to equilibrium */
  PetscInt   static_max_it, static_its;

  /* the contact points of the last step, couple order, every rank (MBCSolverGetContactPoints) */
  struct {
    PetscInt   n;
    PetscReal *lam, *x, *nrm, *force, *traction, *pressure, *gap, *area, *x0, *slip;
    PetscInt  *state;
    int       *couple, *istate;
  } cpts;

  /* energy bookkeeping (dynamic) */
  PetscReal work, dissipated;
  /* energy bookkeeping (dynamic): the work the step's mean contact force z takes from the bodies,
     -z . H^T du summed over the steps, tangential (friction) and normal */
  PetscReal wfriction, wcontact;

  /* long runs (solveroutput.c, solvermonitor.c): wall-clock times of the stepping's start and
     of the last monitored step */
  PetscLogDouble t_start, t_last;
  PetscInt64     h5_size; /* bytes of the result file at its last commit */
  PetscInt       xmf_outputs; /* outputs in the XDMF index on disk */
  FILE          *reactions_csv; /* solveroutputreaction.c */
};

PETSC_EXTERN PetscLogEvent MBC_FlexibilityAssemble;

PETSC_INTERN PetscErrorCode MBCSolverDecompose(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputOpen(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputStep(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputClose(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputReactionsOpen(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputReactionsStep(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputContactOpen(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputContactStep(MBCSolver, PetscBool);
PETSC_INTERN PetscErrorCode MBCSolverOutputContactClose(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverContactPointsFree(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputContactXdmf(MBCSolver, FILE *, PetscInt);
PETSC_INTERN PetscErrorCode MBCSolverOutputBodiesOpen(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputBodiesStep(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputBodiesClose(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputBodiesXdmf(MBCSolver, FILE *, PetscInt);
PETSC_INTERN PetscErrorCode MBCSolverEnergy(MBCSolver, PetscReal[MBC_NENERGY]);
PETSC_INTERN PetscErrorCode MBCSolverMonitorTiming(MBCSolver, char[], size_t);
PETSC_INTERN PetscErrorCode MBCSolverContactSetUp(MBCSolver, PetscInt, PetscInt[]);
PETSC_INTERN PetscErrorCode MBCSolverContactSolve(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverContactStepBegin(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverContactStepAbandon(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverContactRigidRHS(MBCSolver);
PETSC_INTERN PetscBool      MBCSolverPointTouches(const MBCCouple *, PetscInt, PetscInt);
PETSC_INTERN PetscErrorCode MBCSolverContactRigidMotion(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverContactDestroy(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverContactToBodies(MBCSolver, Vec);
PETSC_INTERN PetscErrorCode MBCSolverContactGapRate(MBCSolver, Vec);
PETSC_INTERN PetscErrorCode MBCSolverContactGather(MBCSolver, Vec, PetscReal[]);
PETSC_INTERN PetscErrorCode MBCSolverContactStates(MBCSolver, PetscInt[3], PetscInt[], PetscReal[]);
