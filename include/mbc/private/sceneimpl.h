/* Private: the scene as read from the scene file (docs/scene-h5.md). */
#pragma once

#include <mbcontact.h>
#include <petsc/private/petscimpl.h>
#include <petscds.h>
#include <petscviewerhdf5.h>

#define MBC_NAME_LEN 256
/* Friction coefficients above this are refused: mu = 1e3 is a friction angle of 89.94 degrees. */
#define MBC_MAX_MU 1e3
/* Nonzero material constants (E, density, damping) outside [MIN, MAX] are refused: no material in
   any unit system, and K, M and the energies made from them (squares) would leave double precision
   (E = 1e308 gave a "degenerate cell", E = 1e-308 ran to exit 0). */
#define MBC_MATERIAL_MIN 1e-100
#define MBC_MATERIAL_MAX 1e100
/* Step counts above this are refused (one FE solve per step; the output reserves memory per step). */
#define MBC_MAX_STEPS 1e7

typedef enum {
  MBC_TIME_CONSTANT, /* present from the start: part of the initial static state */
  MBC_TIME_SUDDEN,   /* full value for t >= 0, body at rest at t = 0 */
  MBC_TIME_TABLE     /* factor from a time table, body at rest at t = 0 */
} MBCTimeKind;
PETSC_INTERN const char *const MBCTimeKinds[];

typedef enum {
  MBC_LOAD_GRAVITY,
  MBC_LOAD_BODY_FORCE,
  MBC_LOAD_PRESSURE,
  MBC_LOAD_TRACTION,
  MBC_LOAD_HYDROSTATIC, /* p = unit_weight (level - x_axis) below the level, against the outward normal */
  MBC_LOAD_GROUND_ACCELERATION, /* the base's acceleration a_g(t) = vector f(t): -(M + M_added) a_g on a body
                                  in relative motion; 2 rho c v_incident(t) on the absorbing input surfaces
                                  of a scene in absolute motion (bodyabsorbing.c) */
  MBC_LOAD_NODAL_FORCE, /* vector times a weight at each of its nodes (1: a force per node) */
  MBC_LOAD_LINE_FORCE,  /* vector times int N_i ds at each node of its lines (a force per length) */
  MBC_LOAD_UPLIFT       /* a couple's uplift on one of its surfaces (bodyuplift.c): made by the prep from the couple's `uplift` */
} MBCLoadKind;
PETSC_INTERN const char *const MBCLoadKinds[];

typedef struct {
  PetscInt   n;
  PetscReal *t, *f;
} MBCTimeTable;

typedef struct {
  char      name[MBC_NAME_LEN], cell_type[16]; /* tet4 hex8 wedge6 pyr5 mixed (of the four) tet10 surface (a rigid surface) */
  char      element[16]; /* bodies with hex cells: "hex8" | "hex8i" | "hex8b" | "" (the solver's default) */
  PetscInt  num_cells, num_vertices;
  PetscInt  num_nodes; /* the vertices and tet10's midside nodes (numbered after the vertices) */
  PetscReal E, nu, density, damping, rayleigh_alpha, rayleigh_beta;
  PetscBool massless; /* no inertia in a dynamic analysis (a massless foundation) */
  PetscInt *midside;  /* tet10: per midside node the two vertices of its edge (scene order), 2 each */
  PetscReal *midside_x; /* and its position, 3 each */
  PetscBool rigid;    /* six DOFs: the reference point's translation and the rotation about it (bodyrigidbody.c) */
  PetscReal reference[3], rigid_mass, rigid_inertia[9]; /* mass and inertia about the reference: 0 = from the mesh */
  PetscReal *initial_u, *initial_v; /* initial displacement and velocity per node, scene order (NULL: none) */
} MBCBodyDesc;

typedef struct {
  char      name[MBC_NAME_LEN];
  PetscInt  id, num_faces;
} MBCSurfaceDesc;

/* Uplift on a couple's faces (docs/scene.md, couples' `uplift`; bodyuplift.c): a pressure along s =
   (x - origin) . direction, 0 <= s <= length, by the heel-to-toe law with a drain line or by a
   table; with penetration the reservoir's pressure unit_weight (level - x_axis) where the joint is
   open from the heel (s < the wet length the solver finds, solveruplift.c). */
typedef struct {
  PetscBool  on;
  PetscReal  origin[3], direction[3], length; /* direction: unit */
  PetscReal  lateral[5];         /* the joint's lateral axis t (unit) and the master faces' range along it: 0 beyond */
  PetscInt   nzones;             /* the master bodies' ranges along t (disjoint, ascending), each with its own wet front */
  PetscReal *zones;              /* lo, hi each */
  PetscInt  *zone_of_body;       /* per body of the scene: the zone of its master faces (-1: none) */
  PetscReal  unit_weight, heel_head, tail_head;
  PetscReal  drain, efficiency;  /* the drain line's s (< 0: no drains) and efficiency in [0, 1] */
  PetscInt   ntable;             /* > 0: pressure by the table (s, p) instead of the law */
  PetscReal *table;
  PetscBool  penetration;        /* water enters the open joint from the heel */
  PetscReal  level, threshold;   /* the reservoir's level along axis; a point is open at pressure <= threshold */
  PetscInt   axis;
} MBCUpliftDesc;

/* (x - origin) . axis: a point's position along the uplift's direction, or across it (lateral) */
static inline PetscReal MBCUpliftAlong(const MBCUpliftDesc *u, const PetscReal axis[], const PetscReal x[3])
{
  return (x[0] - u->origin[0]) * axis[0] + (x[1] - u->origin[1]) * axis[1] + (x[2] - u->origin[2]) * axis[2];
}

typedef struct {
  PetscInt  k;
  PetscReal mu;
  MBCUpliftDesc uplift;
  PetscReal cohesion, tensile, mu_residual; /* the joint law (docs/dam.md): cohesion 0 = unbonded Coulomb contact */
  PetscReal softening; /* softening_displacement: the relative displacement over which the bond softens linearly (0: brittle) */
  char     *master, *slave; /* surface names joined by "," */
  PetscReal *master_faces, *slave_faces; /* per body: its faces on each side (weights of the decomposition) */
  PetscInt   nexclude, *exclude; /* master nodes taken out of contact: (body, vertex in scene order) each */
  PetscInt   sliding; /* its `sliding`: 1 small, 0 finite, -1 not given (-mbc_contact_sliding's default) */
} MBCCoupleDesc;

typedef struct {
  char        surface[MBC_NAME_LEN];
  PetscInt    surface_id, component, time_function; /* surface_id -1: on nodes or a rigid body; component 3..5: a rotation */
  PetscReal   value;
  MBCTimeKind time;
  PetscInt    body;           /* a rigid body whose motion it prescribes, else -1 */
  PetscInt    nnodes, *nodes; /* on nodes: (body, node in scene order) each */
} MBCDirichletDesc;

typedef struct {
  MBCLoadKind kind;
  PetscReal   vector[3], value;
  PetscReal   level, unit_weight; /* hydrostatic */
  PetscInt    axis;               /* hydrostatic: 0, 1, 2 for x, y, z (up) */
  char        surface[MBC_NAME_LEN];
  PetscInt    surface_id, time_function;
  char       *bodies; /* body names joined by ",", "" for all */
  MBCTimeKind time;
  PetscInt    stage;  /* acts from this analysis stage on (0: from the start) */
  PetscInt    velocity_function, displacement_function; /* ground acceleration: the record's v and d tables */
  PetscInt    nnodes, *nodes; /* nodal and line forces: (body, node) each */
  PetscReal  *weights;        /* and the node's weight */
  PetscInt    couple, side;   /* uplift: the couple's index in the scene, and 0: its master surface, 1: slave */
} MBCLoadDesc;

/* Discrete springs and dashpots (bodyspring.c): at each node, to the ground or to its partner node of
   the same body, a stiffness and a damping along x, y, z. */
typedef struct {
  PetscReal k[3], c[3];
  PetscInt  n, *nodes, *to; /* (body, node) each; to: NULL (the ground) or the partners */
} MBCSpringDesc;

/* Westergaard's added mass of a reservoir on a wetted surface (bodyaddedmass.c). */
typedef struct {
  char      surface[MBC_NAME_LEN];
  PetscInt  surface_id, axis;      /* axis: 0, 1, 2 = x, y, z, up */
  PetscReal density, level, bottom; /* the water's density, the free surface and the floor along axis */
} MBCAddedMassDesc;

typedef enum {
  MBC_INPUT_NONE,     /* dashpots only */
  MBC_INPUT_OUTCROP,  /* the record is the outcrop motion: the incident wave is half of it */
  MBC_INPUT_INCIDENT  /* the record is the upgoing incident wave at this boundary */
} MBCAbsorbingInput;
PETSC_INTERN const char *const MBCAbsorbingInputs[];

/* Lysmer-Kuhlemeyer dashpots on a truncated boundary (bodyabsorbing.c). */
typedef struct {
  char              surface[MBC_NAME_LEN];
  PetscInt          surface_id;
  MBCAbsorbingInput input;
} MBCAbsorbingDesc;

/* One analysis stage (docs/scene.md, stages): from start_time, where the stage before ends, to
   final_time; it starts from the state the stage before left. */
typedef struct {
  char            name[MBC_NAME_LEN];
  MBCAnalysisType analysis;
  MBCMassType     mass;
  PetscReal       start_time, dt, final_time, newmark_beta, newmark_gamma;
  PetscReal       alpha_m, alpha_f; /* generalized-alpha's weights (0, 0: Newmark; 0, -alpha: HHT) */
  char            scheme[32];       /* newmark | hht | generalized_alpha */
} MBCStageDesc;

typedef struct {
  char      name[MBC_NAME_LEN], body[MBC_NAME_LEN];
  PetscReal x[3];
} MBCPointDesc;

typedef struct _MBCSceneOps *MBCSceneOps;
struct _MBCSceneOps {
  PetscErrorCode (*view)(MBCScene, PetscViewer);
};

struct _n_MBCScene {
  PETSCHEADER(struct _MBCSceneOps);
  char            filename[PETSC_MAX_PATH_LEN], title[MBC_NAME_LEN];
  MBCAnalysisType analysis;
  MBCMassType     mass;
  PetscReal       dt, final_time, newmark_beta, newmark_gamma;
  PetscReal       alpha_m, alpha_f; /* generalized-alpha (solvergenalpha.c); 0, 0: Newmark */
  char            scheme[32];

  PetscInt          nbodies, nsurfaces, ncouples, ntables, ndirichlet, nloads, npoints;
  PetscInt          nstages;   /* 0: one analysis, the settings above */
  MBCStageDesc     *stages;    /* the first one's settings are also those above */
  PetscBool         has_dynamic; /* some stage (or the analysis) is dynamic: the bodies need M */
  MBCBodyDesc      *bodies;
  MBCSurfaceDesc   *surfaces;
  MBCCoupleDesc    *couples;
  MBCTimeTable     *tables;
  MBCDirichletDesc *dirichlet;
  MBCLoadDesc      *loads;
  MBCPointDesc     *points;
  PetscInt          naddedmass, nabsorbing;
  MBCAddedMassDesc *addedmass;
  MBCAbsorbingDesc *absorbing;
  PetscInt          nsprings;
  MBCSpringDesc    *springs;
  PetscBool         absolute;  /* some absorbing surface takes the ground motion in: every body moves in absolute motion */
  PetscInt          modal_modes; /* modal analysis: how many modes */
  PetscBool         modal_tie;   /* and whether the couples are tied */

  PetscInt  output_every;
  PetscBool output_displacement, output_stress, output_energy;
  PetscBool output_envelope; /* per cell the largest principal stress over time and its time */
};

PETSC_EXTERN PetscErrorCode MBCTimeFactor(MBCScene, MBCTimeKind, PetscInt, PetscReal, PetscReal *);
PETSC_INTERN PetscErrorCode MBCSceneCheckMeshes(MBCScene, hid_t);
PETSC_INTERN PetscErrorCode MBCSceneCheckStages(MBCScene);
PETSC_INTERN PetscErrorCode MBCLoadAppliesToBody(MBCLoadDesc *, const char[], PetscBool *);
PETSC_INTERN PetscErrorCode MBCSceneRecord(MBCScene, MBCLoadDesc *, PetscReal, PetscReal *, PetscReal *, PetscReal *);
PETSC_INTERN PetscErrorCode MBCSceneGroundMotion(MBCScene, PetscInt, PetscReal, PetscReal[3], PetscReal[3], PetscReal[3]);
