/* Private: the solver, the bodies of a scene and their time stepping. */
#pragma once

#include <mbc/private/interfaceimpl.h>
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
  PetscInt   nv, nc, nvpc;   /* the scene's nodes (vertices and tet10's midside nodes), cells, nodes per cell (the most: -1 pads) */
  PetscInt   ntopo, topostart, ntoporows; /* a body of several cell types: XDMF's Mixed topology, its length and this rank's part */
  PetscInt   vstart, nvrows; /* this rank writes vertex rows [vstart, vstart + nvrows) */
  PetscInt   cstart, ncrows; /* and cell rows [cstart, cstart + ncrows) (0 rows off the body) */
  PetscSF    vsf, csf;       /* values of owned vertices (3 each) and cells (6 each) -> their rows; NULL off the body */
  PetscInt   nvown, *vrow;   /* owned vertices: local row of each in the displacement Vec */
  PetscInt   ncown, *crow;   /* owned cells: local row of each in the stress Vec */
  PetscReal *leaf, *root;    /* work: values of the owned points; this rank's rows (displacement, then stress) */
} MBCBodyOutput;

/* The dynamic step's integrator (solvergenalpha.c): Newmark, HHT-alpha or generalized-alpha. */
typedef enum {
  MBC_SCHEME_NEWMARK,
  MBC_SCHEME_HHT,
  MBC_SCHEME_GALPHA
} MBCSchemeType;
PETSC_INTERN const char *const MBCSchemeTypes[];

#define MBC_NENERGY 6 /* kinetic, strain, external work, damping, friction, normal contact */

/* One analysis stage of the run (the scene's stages, or the one analysis): its steps are
   step0 + 1 .. step0 + nsteps of the run, from t0 to t1 (solverstage.c). */
typedef struct {
  MBCAnalysisType analysis;
  PetscReal       t0, t1, dt, beta, gamma, am, af;
  MBCSchemeType   scheme;
  PetscInt        step0, nsteps;
  PetscLogStage   log; /* -log_view */
} MBCSolverStage;

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

  MBCAnalysisType analysis; /* of the current stage, as dt, beta, gamma */
  MBCMassType     mass;
  PetscBool       has_dynamic; /* some stage of this run is dynamic: the bodies need M */
  PetscReal       dt, final_time, beta, gamma;
  MBCSchemeType   scheme;       /* of the current stage, with its generalized-alpha weights */
  PetscReal       am, af;
  PetscInt        nsteps, step; /* of the whole run, over its stages */
  PetscReal       time;
  PetscInt        nstages, istage; /* the analysis stages, the current one */
  MBCSolverStage *stages;
  PetscBool       log_pushed;  /* stages[istage].log is pushed */

  PetscInt  nbodies;
  MBCBody  *bodies;       /* NULL where this rank is not in the body */
  PetscMPIInt *body_first_rank, *body_nranks;
  PetscReal   decomp_cut, decomp_imbalance; /* contact faces between bodies on different ranks; largest rank work / mean */

  /* output */
  char      output[PETSC_MAX_PATH_LEN];
  PetscInt  output_every, noutputs;
  PetscReal *output_times;
  PetscInt *output_npoints; /* contact points written at each output (XDMF) */
  int      *output_cuts;    /* step halvings since the output before (/cuts in the result file) */
  int      *output_stage;   /* the analysis stage of each output (/stage) */
  PetscInt  cuts_written;   /* ncuts at the last output */
  char      h5file[PETSC_MAX_PATH_LEN]; /* <output>.h5: every body and the contact points, written collectively */
  int64_t   h5;           /* its hid_t on every rank, -1 when not open */
  MBCBodyOutput *bout;    /* per body, where the file has fields */
  FILE     *points_csv, *energy_csv, *contact_csv;
  MBCPointLocation *points;
  PetscBool monitor, view;

  MBCContact   contact;   /* the search; NULL when the scene has no couples */
  MBCInterface iface;     /* H, D, q, the multipliers and the per-point bookkeeping; NULL when the scene has no couples */
  PetscBool  search_only;
  PetscInt   dblock;      /* -mbc_contact_block, for the interface */
  PetscInt   droute;      /* -mbc_d_route: MBCDRoute (interfaceimpl.h), auto by default */
  PetscBool  rows_even;   /* -mbc_contact_rows_even */
  PetscReal  joint_tol, joint_frac; /* -mbc_joint_break_rtol, -mbc_joint_break_fraction (interfacejoint.c) */
  PetscReal  schur_max_mb; /* -mbc_d_schur_max_mb */
  PetscReal  dense_max_mb; /* -mbc_d_dense_max_mb */
  PetscReal  solves_max;   /* -mbc_d_solves_max */
  PetscInt   coarse_points; /* -mbc_d_coarse_points */
  PetscReal  coarse_max_mb; /* -mbc_d_coarse_max_mb */
  PetscReal  memory_mb;     /* -mbc_memory_mb: what this rank may hold (-1: its share of the node's available memory; 0: no check) */
  char       fclib_file[PETSC_MAX_PATH_LEN]; /* -mbc_fclib_write: the multiplier problem of step fclib_step */
  PetscInt   fclib_step;

  /* step control: a dynamic step whose contact solve fails, a static load step that does not
     converge, is cut in two, down to dt_min */
  PetscBool  dt_cut, contact_may_fail, contact_failed, force_build;
  PetscBool  contact_rebuilt; /* the last SolverContact found other pairs and rebuilt H and D */
  PetscReal  dt_min;
  PetscInt   level, ncuts; /* the current step is dt / 2^level; steps cut so far */
  PetscInt   start_level, good_steps, deepest; /* a scene step starts at dt / 2^start_level; steps since without a cut; finest level of this step */

  /* static analysis: equilibrium iterations, stabilisation of bodies held only by contact */
  PetscReal  static_stabilize, static_rtol;
  PetscBool  static_stabilized, static_floating; /* some body has the spring, or free rigid modes: iterate to equilibrium */
  PetscInt   static_max_it, static_its;

  /* the contact points of the last step, couple order, every rank (MBCSolverGetContactPoints) */
  struct {
    PetscInt   n;
    PetscReal *lam, *x, *nrm, *force, *traction, *pressure, *gap, *area, *x0, *slip;
    PetscInt  *state;
    int       *couple, *istate;
    PetscInt  *bonded; /* bonded couples (else NULL): 1 while the point's bond holds */
    PetscReal *tbreak; /*   and the time it broke, NaN if it did not */
  } cpts;

  /* uplift (solveruplift.c): per zone of each couple of the scene (couple i's from off[i]) the wet
     length from the heel (w: the new ones, work), and per couple on its master side int p dA and
     int p x dA (4 each) for a unit time factor */
  struct {
    PetscBool  on, set;
    PetscBool  restored; /* wet read from a checkpoint: the first step after a restart takes it */
    PetscInt  *off;
    PetscReal *wet, *w, *r;
  } uplift;

  /* energy bookkeeping (dynamic) */
  PetscReal work, dissipated;
  /* energy bookkeeping (dynamic): the work the step's mean contact force z takes from the bodies,
     -z . H^T du summed over the steps, tangential (friction) and normal */
  PetscReal wfriction, wcontact;

  /* long runs (solveroutput.c, solvermonitor.c): wall-clock times of the stepping's start and
     of the last monitored step */
  PetscLogDouble t_start, t_last;
  PetscInt       step_its; /* contact solve iterations of the step so far (all its solves) */
  char           contact_line[256]; /* the monitor's line of the last contact solve, printed with the states where they are final (MBCSolverMonitorContact) */
  PetscInt       step_begin; /* the step the stepping started from (a restart's) */
  PetscInt64     h5_size; /* bytes of the result file at its last commit */
  PetscInt       xmf_outputs; /* outputs in the XDMF index on disk */
  FILE          *reactions_csv; /* solveroutputreaction.c */

  /* checkpoint and restart (solvercheckpoint.c) */
  PetscInt       checkpoint_every; /* -mbc_checkpoint_every: steps (0: at a signal only) */
  char           restart[PETSC_MAX_PATH_LEN]; /* -mbc_restart: the checkpoint to go on from */
  PetscBool      restarting;  /* set-up for a restart: the state comes from the file */
  MBCBodyOutput *ckpt;        /* per body: its vertex map (scene order rows) */
  Vec           *ubuild, *ugsbuild; /* per body: u when H was built, and at the global search it used (the search replayed at a restart) */

  /* modal analysis (solvermodal.c) */
  PetscInt   modal_nev;   /* -mbc_modal_nev: modes (default the scene's) */
  PetscBool  modal_tie;   /* -mbc_modal_tie: the couples tied (default the scene's) */
  PetscReal *modal_freq;  /* the frequencies found, Hz */
};

PETSC_INTERN PetscErrorCode MBCSolverDecompose(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverContactExclusions(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputOpen(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputStep(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputClose(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputReactionsOpen(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputReactionsStep(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputContactOpen(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputContactStep(MBCSolver, PetscBool);
PETSC_INTERN PetscErrorCode MBCSolverOutputContactClose(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverContactPointsFree(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverUpliftUpdate(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverUpliftResultant(MBCSolver, PetscInt, PetscReal[5]);
PETSC_INTERN PetscErrorCode MBCSolverUpliftDestroy(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverUpliftNext(MBCSolver, PetscInt *, const PetscReal **);
PETSC_INTERN PetscErrorCode MBCSolverUpliftRestore(MBCSolver, PetscInt, const PetscReal[]);
PETSC_INTERN PetscErrorCode MBCSolverOutputContactXdmf(MBCSolver, FILE *, PetscInt);
PETSC_INTERN PetscErrorCode MBCSolverOutputBodiesOpen(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputBodiesStep(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputBodiesClose(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverOutputBodiesXdmf(MBCSolver, FILE *, PetscInt);
PETSC_INTERN PetscErrorCode MBCSolverEnergy(MBCSolver, PetscReal[MBC_NENERGY]);
PETSC_INTERN PetscErrorCode MBCSolverMonitorTiming(MBCSolver, char[], size_t);
PETSC_INTERN PetscErrorCode MBCSolverMonitorContact(MBCSolver, MBCMultiplier);
PETSC_INTERN PetscErrorCode MBCSolverStagesSetUp(MBCSolver, PetscBool);
PETSC_INTERN PetscErrorCode MBCBodyVertexMapCreate(MBCBody, MBCBodyOutput *, PetscInt **, PetscInt **);
PETSC_INTERN PetscErrorCode MBCSolverCheckpointWrite(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverRestart(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverCheckpointTrack(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverCheckpointFree(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverStageResume(MBCSolver, PetscInt);
PETSC_INTERN PetscErrorCode MBCSolverStageLog(MBCSolver, PetscInt);
PETSC_INTERN PetscReal      MBCSolverStageTime(MBCSolver, PetscInt);
PETSC_INTERN PetscErrorCode MBCSolverModalSetFromOptions(MBCSolver);
PETSC_INTERN PetscErrorCode MBCSolverModalSolve(MBCSolver);
PETSC_INTERN MBCTimeCoefficients MBCTimeScheme(PetscReal, PetscReal, PetscReal, PetscReal, PetscReal);
PETSC_INTERN PetscReal      MBCTimeContactWeight(PetscReal, PetscReal, PetscReal);
PETSC_INTERN PetscBool      MBCTimeContactThroughAcceleration(PetscReal);
PETSC_INTERN PetscErrorCode MBCSolverSchemeSetFromOptions(MBCSolver, PetscOptionItems *, PetscBool *);
PETSC_INTERN MBCSchemeType  MBCSchemeFromName(const char *);
