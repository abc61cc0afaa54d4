/* The solver: places bodies on sub-communicators, sets them up, steps in time. */
#include <mbc/private/solverimpl.h>
#include <mbc/private/h5util.h>
#include <ctype.h>

PetscErrorCode MBCSolverCreate(MPI_Comm comm, MBCSolver *solver)
{
  MBCSolver s;

  PetscFunctionBegin;
  PetscValidPointer(solver, 2);
  PetscCall(MBCInitializePackage());
  PetscCall(PetscHeaderCreate(s, MBC_SOLVER_CLASSID, "MBCSolver", "mbcontact solver", "MBCSolver", comm, MBCSolverDestroy, MBCSolverView));
  s->comm             = comm;
  s->h5               = -1;
  s->fclib_step       = -1;
  s->static_stabilize = 0; /* off: the free bodies' exact rigid modes */
  s->static_rtol      = 1e-6;
  s->static_max_it    = 50;
  s->dt_cut           = PETSC_TRUE;
  s->dt_min           = -1;
  s->dblock           = 256;
  s->joint_tol        = 1e-6;
  s->joint_frac       = 1;
  s->droute           = MBC_D_ROUTE_AUTO; /* auto: matrix-free, Schur or solves by size (docs/performance.md) */
  s->rows_even        = PETSC_TRUE;
  s->schur_max_mb     = 8192; /* S^-1 and MUMPS's factorization with the Schur set: 4.3 GB at the 400k-DOF dam's foundation */
  s->dense_max_mb     = 4096; /* up to ~15 000 multipliers (docs/performance.md) */
  s->coarse_points    = 16; /* the 200k static dam: 218 products became 155, 5 s of solves for 17 s of products saved (docs/performance.md) */
  s->coarse_max_mb    = 256;
  s->memory_mb        = -1;
  s->solves_max       = 4096; /* a matrix-free multiplier solve took 60 to 100 products per static iteration (docs/performance.md) */
  *solver = s;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverSetScene(MBCSolver s, MBCScene scene)
{
  size_t len;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  PetscValidHeaderSpecific(scene, MBC_SCENE_CLASSID, 2);
  PetscCheck(!s->setupcalled, s->comm, PETSC_ERR_ARG_WRONGSTATE, "MBCSolverSetScene(%s): the solver is already set up with scene %s; create a new solver", scene->filename, s->scene->filename);
  PetscCall(PetscObjectReference((PetscObject)scene)); /* the caller keeps its own */
  PetscCall(MBCSceneDestroy(&s->scene));
  s->scene        = scene;
  s->analysis     = scene->analysis;
  s->mass         = scene->mass;
  s->has_dynamic  = scene->has_dynamic;
  s->dt           = scene->dt;
  s->final_time   = scene->final_time;
  s->beta         = scene->newmark_beta;
  s->gamma        = scene->newmark_gamma;
  s->am           = scene->alpha_m;
  s->af           = scene->alpha_f;
  s->scheme       = MBCSchemeFromName(scene->scheme);
  s->output_every = scene->output_every;
  PetscCall(PetscStrncpy(s->output, scene->filename, sizeof(s->output)));
  PetscCall(PetscStrlen(s->output, &len));
  if (len > 3 && !strcmp(s->output + len - 3, ".h5")) s->output[len - 3] = 0;
  PetscCall(PetscStrlcat(s->output, "_result", sizeof(s->output)));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverSetFromOptions(MBCSolver s)
{
  PetscEnum analysis = (PetscEnum)s->analysis, mass = (PetscEnum)s->mass;
  PetscBool set[6] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};

  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  PetscCheck(s->scene, s->comm, PETSC_ERR_ARG_WRONGSTATE, "Call MBCSolverSetScene() before MBCSolverSetFromOptions()");
  PetscObjectOptionsBegin((PetscObject)s);
  PetscCall(PetscOptionsEnum("-mbc_analysis", "Analysis type (overrides the scene's)", "MBCSolverSetFromOptions", MBCAnalysisTypes, analysis, &analysis, &set[0]));
  PetscCall(PetscOptionsEnum("-mbc_mass", "Mass matrix", "MBCSolverSetFromOptions", MBCMassTypes, mass, &mass, &set[1]));
  PetscCall(PetscOptionsReal("-mbc_dt", "Time (or load) step", "MBCSolverSetFromOptions", s->dt, &s->dt, &set[2]));
  PetscCall(PetscOptionsReal("-mbc_final_time", "Final time", "MBCSolverSetFromOptions", s->final_time, &s->final_time, NULL));
  PetscCall(PetscOptionsReal("-mbc_newmark_beta", "Newmark beta", "MBCSolverSetFromOptions", s->beta, &s->beta, &set[3]));
  PetscCall(PetscOptionsReal("-mbc_newmark_gamma", "Newmark gamma", "MBCSolverSetFromOptions", s->gamma, &s->gamma, &set[4]));
  PetscCall(MBCSolverSchemeSetFromOptions(s, PetscOptionsObject, &set[5]));
  PetscCheck(!(set[5] && s->scheme != MBC_SCHEME_NEWMARK && (set[3] || set[4])), s->comm, PETSC_ERR_ARG_INCOMP, "-mbc_newmark_beta and -mbc_newmark_gamma are Newmark's: the %s scheme sets them from its own parameters", MBCSchemeTypes[s->scheme]);
  PetscCall(PetscOptionsInt("-mbc_output_every", "Write fields every this many steps", "MBCSolverSetFromOptions", s->output_every, &s->output_every, NULL));
  PetscCall(PetscOptionsString("-mbc_output", "Prefix of the result files", "MBCSolverSetFromOptions", s->output, s->output, sizeof(s->output), NULL));
  PetscCall(PetscOptionsBool("-mbc_monitor", "Print a line per step", "MBCSolverSetFromOptions", s->monitor, &s->monitor, NULL));
  PetscCall(PetscOptionsBool("-mbc_view", "Print the scene and the decomposition", "MBCSolverSetFromOptions", s->view, &s->view, NULL));
  PetscCall(PetscOptionsBool("-mbc_contact_search_only", "Search contact on the undeformed bodies, report, stop", "MBCSolverSetFromOptions", s->search_only, &s->search_only, NULL));
  PetscCall(PetscOptionsString("-mbc_fclib_write", "Write the contact multiplier problem of step -mbc_fclib_write_step to this FCLIB file", "MBCSolverSetFromOptions", s->fclib_file, s->fclib_file, sizeof(s->fclib_file), NULL));
  {
    PetscBool set_step, set_stab;
    PetscCall(PetscOptionsInt("-mbc_fclib_write_step", "Step whose multiplier problem -mbc_fclib_write writes (default: the last)", "MBCSolverSetFromOptions", s->fclib_step, &s->fclib_step, &set_step));
    PetscCheck(!set_step || s->fclib_step >= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_fclib_write_step %" PetscInt_FMT ": must be a step number >= 1 (without it, the last step)", s->fclib_step);
    PetscCall(PetscOptionsReal("-mbc_static_stabilize", "Static: bodies their supports leave free get a spring epsilon diag(K) to the last iterate (> 0) instead of their exact rigid-body modes (default, or 0)", "MBCSolverSetFromOptions", s->static_stabilize, &s->static_stabilize, &set_stab));
    PetscCheck(!set_stab || (s->static_stabilize >= 0 && !PetscIsInfOrNanReal(s->static_stabilize)), s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_static_stabilize %g: must be >= 0 and finite (0: the exact rigid-body modes, the default)", (double)s->static_stabilize);
  }
  PetscCall(PetscOptionsReal("-mbc_static_rtol", "Static: equilibrium iterations stop when the out-of-balance force max|A du| <= rtol max|K u|", "MBCSolverSetFromOptions", s->static_rtol, &s->static_rtol, NULL));
  PetscCall(PetscOptionsBool("-mbc_contact_rows_even", "The contact points' rows of W (and the multiplier problem's) split evenly over the ranks, in the order of the ranks that compute most of each row, instead of each on that rank: the multiplier solve's row-wise work (products with W and the kept inverse) is the rows' owners'", "MBCSolverSetFromOptions", s->rows_even, &s->rows_even, NULL));
  PetscCall(PetscOptionsReal("-mbc_joint_break_rtol", "Bonded couples: a bond breaks where its traction lies within this fraction of its apex force (c/mu) A of the cone's boundary", "MBCSolverSetFromOptions", s->joint_tol, &s->joint_tol, NULL));
  PetscCheck(s->joint_tol >= 0 && s->joint_tol < 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_joint_break_rtol %g must lie in [0, 1)", (double)s->joint_tol);
  PetscCall(PetscOptionsReal("-mbc_joint_break_fraction", "Bonded couples: each solve of a step's cascade breaks the bonds whose excess over the cone is within this fraction of the largest (1: every bond beyond; 0: the most loaded, and those tied with it)", "MBCSolverSetFromOptions", s->joint_frac, &s->joint_frac, NULL));
  PetscCheck(s->joint_frac >= 0 && s->joint_frac <= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_joint_break_fraction %g must lie in [0, 1]", (double)s->joint_frac);
  PetscCall(PetscOptionsInt("-mbc_contact_block", "Columns of A^-1 H per multi-right-hand-side solve while D is built (memory: DOFs x block per body)", "MBCSolverSetFromOptions", s->dblock, &s->dblock, NULL));
  {
    const char *routes[] = {"multirhs", "schur", "auto", "matfree"};
    PetscCall(PetscOptionsEList("-mbc_d_route", "How D_i = H_i^T A_i^-1 H_i is had: dense from multi-right-hand-side solves with the body's factor, dense through the Schur complement of A_i onto its contact DOFs in a MUMPS factorization (bodies on one rank), auto: matrix-free where the dense D does not fit in -mbc_d_dense_max_mb or would take more than -mbc_d_solves_max solves to build, else per body the Schur complement where it fits in -mbc_d_schur_max_mb, else the solves; or matfree: never stored, a solve per body per product (newton type only; docs/performance.md)", "MBCSolverSetFromOptions", routes, 4, routes[s->droute], &s->droute, NULL));
    PetscCall(PetscOptionsReal("-mbc_d_schur_max_mb", "-mbc_d_route auto: the most memory, in MB, a body's Schur route may take (S^-1, |contact DOFs|^2 doubles, and MUMPS's estimate for the factorization with the Schur set)", "MBCSolverSetFromOptions", s->schur_max_mb, &s->schur_max_mb, NULL));
    PetscCall(PetscOptionsReal("-mbc_d_dense_max_mb", "-mbc_d_route auto: beyond this many MB for the dense D and the Newton matrix, D is matrix-free", "MBCSolverSetFromOptions", s->dense_max_mb, &s->dense_max_mb, NULL));
    PetscCheck(s->schur_max_mb >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_d_schur_max_mb %g: must be >= 0", (double)s->schur_max_mb);
    PetscCall(PetscOptionsReal("-mbc_d_solves_max", "-mbc_d_route auto: beyond this many solves to build the dense D (bodies the Schur route does not fit), D is matrix-free", "MBCSolverSetFromOptions", s->solves_max, &s->solves_max, NULL));
    PetscCheck(s->dense_max_mb >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_d_dense_max_mb %g: must be >= 0", (double)s->dense_max_mb);
    PetscCheck(s->solves_max >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_d_solves_max %g: must be >= 0", (double)s->solves_max);
    PetscCall(PetscOptionsInt("-mbc_d_coarse_points", "Matrix-free D: contact points per patch of the coarse space that corrects the Krylov Newton steps' preconditioner (0: none)", "MBCSolverSetFromOptions", s->coarse_points, &s->coarse_points, NULL));
    PetscCheck(s->coarse_points >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_d_coarse_points %" PetscInt_FMT ": must be >= 0", s->coarse_points);
    PetscCall(PetscOptionsReal("-mbc_d_coarse_max_mb", "Matrix-free D: the most memory, in MB, W times the coarse space may take (larger patches beyond)", "MBCSolverSetFromOptions", s->coarse_max_mb, &s->coarse_max_mb, NULL));
    PetscCheck(s->coarse_max_mb > 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_d_coarse_max_mb %g: must be > 0", (double)s->coarse_max_mb);
    PetscCheck(!(s->droute == MBC_D_ROUTE_MATFREE && s->fclib_file[0]), s->comm, PETSC_ERR_ARG_INCOMP, "-mbc_fclib_write writes the entries of D, which -mbc_d_route matfree never forms: use another -mbc_d_route");
  }
  PetscCall(PetscOptionsBool("-mbc_dt_cut", "A dynamic step whose contact solve fails, a static load step that does not converge, is done again as two half steps (down to -mbc_dt_min)", "MBCSolverSetFromOptions", s->dt_cut, &s->dt_cut, NULL));
  PetscCall(PetscOptionsReal("-mbc_dt_min", "The smallest step (or load step) a cut may reach (default dt / 1024)", "MBCSolverSetFromOptions", s->dt_min, &s->dt_min, NULL));
  PetscCall(PetscOptionsReal("-mbc_memory_mb", "The memory, in MB, this rank may hold: a body's MUMPS factor that would not fit in what is left of it goes out of core (default: the rank's share of its node's available memory; 0: no check)", "MBCSolverSetFromOptions", s->memory_mb, &s->memory_mb, NULL));
  PetscCheck(s->memory_mb >= 0 || s->memory_mb == -1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_memory_mb %g: must be >= 0", (double)s->memory_mb);
  PetscCall(PetscOptionsInt("-mbc_checkpoint_every", "Write the whole state to <output>_checkpoint.h5 every this many steps (0: only at SIGINT/SIGTERM)", "MBCSolverSetFromOptions", s->checkpoint_every, &s->checkpoint_every, NULL));
  PetscCall(PetscOptionsString("-mbc_restart", "Go on from this checkpoint (the outputs after it go to <output>_restart.h5)", "MBCSolverSetFromOptions", s->restart, s->restart, sizeof(s->restart), NULL));
  PetscCall(PetscOptionsInt("-mbc_static_max_it", "Static: maximum equilibrium iterations per step", "MBCSolverSetFromOptions", s->static_max_it, &s->static_max_it, NULL));
  PetscOptionsEnd();
  s->analysis = (MBCAnalysisType)analysis;
  s->mass     = (MBCMassType)mass;
  /* the solver's own settings, handed to its bodies: the scene stays as its file says, so other
     solvers on it see the same */
  s->has_dynamic = s->scene->nstages ? s->scene->has_dynamic : (PetscBool)(s->analysis == MBC_ANALYSIS_DYNAMIC || s->analysis == MBC_ANALYSIS_MODAL); /* modal: M too */
  PetscCall(MBCSolverModalSetFromOptions(s));
  PetscCheck(s->dt > 0 && PetscIsNormalReal(s->dt), s->comm, PETSC_ERR_ARG_OUTOFRANGE, "Time step -mbc_dt %g must be positive and finite", (double)s->dt);
  PetscCheck(s->final_time >= s->dt * (1 - 1e-12) && PetscIsNormalReal(s->final_time), s->comm, PETSC_ERR_ARG_OUTOFRANGE, "Final time -mbc_final_time %g must be finite and at least one step (%g)", (double)s->final_time, (double)s->dt);
  /* checked before the cast to an integer below (undefined beyond its range); the output
     reserves a few numbers per step up front */
  PetscCheck(s->final_time / s->dt <= MBC_MAX_STEPS, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "Time step -mbc_dt %g to final time -mbc_final_time %g is %.3g steps, more than %g: use a larger dt", (double)s->dt, (double)s->final_time, (double)(s->final_time / s->dt), (double)MBC_MAX_STEPS);
  PetscCheck(s->output_every >= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_output_every %" PetscInt_FMT " must be at least 1", s->output_every);
  if (s->analysis == MBC_ANALYSIS_DYNAMIC && !s->scene->nstages) { /* the stages are checked as read */
    PetscCheck(s->gamma >= 0.5 && s->beta >= 0.25 * (0.5 + s->gamma) * (0.5 + s->gamma) * (1 - 1e-12), s->comm, PETSC_ERR_ARG_OUTOFRANGE, "Newmark beta %g, gamma %g are not unconditionally stable (need gamma >= 1/2, beta >= (1/2 + gamma)^2 / 4)", (double)s->beta, (double)s->gamma);
    for (PetscInt b = 0; b < s->scene->nbodies; b++) PetscCheck(s->scene->bodies[b].density > 0 || s->scene->bodies[b].massless || s->scene->bodies[b].rigid, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "Scene file %s: body '%s' needs a positive density for a dynamic analysis", s->scene->filename, s->scene->bodies[b].name);
  }
  PetscCall(MBCSolverStagesSetUp(s, (PetscBool)(set[0] || set[1] || set[2] || set[3] || set[4] || set[5])));
  if (s->dt_min < 0) s->dt_min = s->dt / 1024;
  PetscCheck(s->dt_min > 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_dt_min %g must be positive", (double)s->dt_min);
  if (s->fclib_step < 0) s->fclib_step = s->nsteps;
  PetscCheck(!s->fclib_file[0] || (s->fclib_step >= 1 && s->fclib_step <= s->nsteps), s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_fclib_write_step %" PetscInt_FMT " is not a step of this run (1 to %" PetscInt_FMT ")", s->fclib_step, s->nsteps);
  PetscCheck(s->static_rtol > 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_static_rtol %g must be positive", (double)s->static_rtol);
  PetscCheck(s->dblock >= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_contact_block %" PetscInt_FMT " must be at least 1", s->dblock);
  PetscCheck(s->checkpoint_every >= 0, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_checkpoint_every %" PetscInt_FMT " must not be negative", s->checkpoint_every);
  if (s->restart[0]) { /* the run before keeps its results */
    size_t len = strlen(s->output);
    if (len < 8 || strcmp(s->output + len - 8, "_restart")) PetscCall(PetscStrlcat(s->output, "_restart", sizeof(s->output)));
  }
  PetscCheck(s->static_max_it >= 1, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "-mbc_static_max_it %" PetscInt_FMT " must be at least 1", s->static_max_it);
  PetscFunctionReturn(0);
}

/* -body_X applies to every body: copy it to -body_<name>_X for each body that does not set
   its own, so every body's KSP has one prefix and options read at solve time (-ksp_view,
   -ksp_monitor) work too. */
static PetscBool IsOptionValue(const char *tok)
{
  return (PetscBool)(tok && (tok[0] != '-' || isdigit((unsigned char)tok[1]) || tok[1] == '.'));
}

/* *mb: this rank's share of its node's available memory plus what it holds now; 0 (no check)
   where the kernel does not say. Collective. */
static PetscErrorCode SolverRankMemory(MPI_Comm comm, PetscReal *mb)
{
  PetscLogDouble rss;
  PetscReal      share;

  PetscFunctionBegin;
  PetscCall(MBCMemoryAvailable(comm, &share));
  PetscCall(PetscMemoryGetCurrentUsage(&rss));
  *mb = share > 0 ? share + rss / 1048576.0 : 0;
  PetscCall(PetscInfo(NULL, "-mbc_memory_mb %g: this rank's share of its node's available memory (%g MB)\n", (double)*mb, (double)share));
  PetscFunctionReturn(0);
}

/* Does option name rest (what follows "-<prefix>body_") already belong to one body ("<name>_...")? */
static PetscBool IsBodyOption(MBCScene scene, const char *rest)
{
  for (PetscInt c = 0; c < scene->nbodies; c++) {
    size_t len = strlen(scene->bodies[c].name);
    if (!strncmp(rest, scene->bodies[c].name, len) && rest[len] == '_') return PETSC_TRUE;
  }
  return PETSC_FALSE;
}

static PetscErrorCode SolverPropagateBodyOptions(MBCSolver s)
{
  char       *all, *save = NULL, **tok, key[256];
  const char *prefix;
  size_t      len, klen;
  int         n = 0;

  PetscFunctionBegin;
  PetscCall(PetscObjectGetOptionsPrefix((PetscObject)s, &prefix));
  PetscCall(PetscSNPrintf(key, sizeof(key), "-%sbody_", prefix ? prefix : ""));
  PetscCall(PetscStrlen(key, &klen));
  PetscCall(PetscOptionsGetAll(NULL, &all));
  PetscCall(PetscStrlen(all, &len));
  PetscCall(PetscMalloc1(len / 2 + 2, &tok));
  for (char *t = strtok_r(all, " ", &save); t; t = strtok_r(NULL, " ", &save)) tok[n++] = t;
  for (int i = 0; i < n; i++) {
    const char *value = (i + 1 < n && IsOptionValue(tok[i + 1])) ? tok[i + 1] : NULL;
    if (strncmp(tok[i], key, klen) || IsOptionValue(tok[i]) || IsBodyOption(s->scene, tok[i] + klen)) continue;
    for (PetscInt b = 0; b < s->scene->nbodies; b++) {
      char      target[2 * MBC_NAME_LEN + 256];
      PetscBool has;
      PetscCall(PetscSNPrintf(target, sizeof(target), "%s%s_%s", key, s->scene->bodies[b].name, tok[i] + klen));
      PetscCall(PetscOptionsHasName(NULL, NULL, target, &has));
      if (!has) PetscCall(PetscOptionsSetValue(NULL, target, value));
    }
  }
  PetscCall(PetscFree(tok));
  PetscCall(PetscFree(all));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverSetUp(MBCSolver s)
{
  MBCScene    scene = s->scene;
  PetscMPIInt rank;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  if (s->setupcalled) PetscFunctionReturn(0);
  PetscCheck(scene, s->comm, PETSC_ERR_ARG_WRONGSTATE, "Call MBCSolverSetScene() first");
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(MBCSolverDecompose(s));
  PetscCall(SolverPropagateBodyOptions(s));
  s->nbodies = scene->nbodies;
  PetscCall(PetscCalloc1(s->nbodies, &s->bodies));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscBool mine = (PetscBool)(rank >= s->body_first_rank[b] && rank < s->body_first_rank[b] + s->body_nranks[b]);
    MPI_Comm  comm;

    PetscCallMPI(MPI_Comm_split(s->comm, mine ? 0 : MPI_UNDEFINED, rank, &comm));
    if (mine) PetscCall(MBCBodyCreate(comm, scene, b, ((PetscObject)s)->prefix, &s->bodies[b]));
  }
  if (s->memory_mb < 0) PetscCall(SolverRankMemory(s->comm, &s->memory_mb));
  for (PetscInt b = 0; b < s->nbodies; b++)
    if (s->bodies[b]) PetscCall(MBCBodySetMemoryLimit(s->bodies[b], s->memory_mb));
  if (!s->search_only)
    for (PetscInt b = 0; b < s->nbodies; b++)
      if (s->bodies[b]) PetscCall(MBCBodySetUp(s->bodies[b], s->has_dynamic, s->mass));
  if (scene->ncouples) {
    PetscCall(MBCContactCreate(s->comm, scene, &s->contact));
    PetscCall(MBCContactSetFromOptions(s->contact, ((PetscObject)s)->prefix));
    PetscCall(MBCSolverContactExclusions(s));
    PetscCall(MBCInterfaceCreate(s->comm, scene, s->contact, s->nbodies, s->bodies, s->body_first_rank, s->body_nranks, ((PetscObject)s)->prefix, &s->iface));
    PetscCall(MBCInterfaceSetBlockSize(s->iface, s->dblock));
    PetscCall(MBCInterfaceSetDRoute(s->iface, s->droute, s->schur_max_mb, s->dense_max_mb, s->solves_max));
    PetscCall(MBCInterfaceSetRowsEven(s->iface, s->rows_even));
    PetscCall(MBCInterfaceSetJointBreak(s->iface, s->joint_tol, s->joint_frac));
    PetscCall(MBCInterfaceSetCoarse(s->iface, s->coarse_points, s->coarse_max_mb));
    PetscCall(MBCInterfaceSetFclibWrite(s->iface, s->fclib_file, s->fclib_step));
  }
  s->setupcalled = PETSC_TRUE;
  if (s->view) PetscCall(MBCSolverView(s, PETSC_VIEWER_STDOUT_(s->comm)));
  PetscCall(PetscObjectViewFromOptions((PetscObject)s, NULL, "-mbc_solver_view"));
  PetscFunctionReturn(0);
}

/* kinetic, strain, external work, damping dissipation (summed over bodies), frictional
   dissipation and the energy taken by the normal contact forces: total = kinetic + strain - work
   + the three dissipations stays at its initial value (0) up to the integrator's error. */
PetscErrorCode MBCSolverEnergy(MBCSolver s, PetscReal energy[MBC_NENERGY])
{
  PetscReal local[2] = {0, 0}, works[2] = {0, 0};

  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody     body = s->bodies[b];
    PetscReal   e[4];
    MPI_Comm    bcomm;
    PetscMPIInt brank;
    if (!body) continue;
    PetscCall(MBCBodyEnergy(body, e));
    PetscCall(MBCBodyGetComm(body, &bcomm));
    PetscCallMPI(MPI_Comm_rank(bcomm, &brank));
    if (brank) continue; /* each body's terms once */
    local[0] += e[0];
    local[1] += e[1];
    works[0] += e[2];
    works[1] += e[3];
  }
  PetscCallMPI(MPI_Allreduce(local, energy, 2, MPIU_REAL, MPI_SUM, s->comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, works, 2, MPIU_REAL, MPI_SUM, s->comm));
  energy[2] = works[0];
  energy[3] = works[1];
  energy[4] = s->wfriction;
  energy[5] = s->wcontact;
  PetscFunctionReturn(0);
}

/* The contact search at the current displacements, then H, X and D rebuilt when the contact
   pairs (couple, master node, slave face, slave nodes of the integrated constraint) changed.
   Dynamic: the acceleration a_n keeps the contact force H_old lambda_n that acted at t_n, so the
   next step is the trapezoidal rule on the forces that act; the lambda_n' carried to the new
   points serves only the complementarity on the step's mean force. (Correcting a_n to H_new
   lambda_n' instead kicked the velocity at every rebuild: on the dynamic Hertz route the faces
   flipped, D was rebuilt 286 times and P drifted from 1305 to 679 N.) */
static PetscErrorCode SolverContact(MBCSolver s)
{
  MBCContact c = s->contact;
  PetscBool  researched, changed;
  PetscInt   n, nmult, *pairs;

  PetscFunctionBegin;
  s->contact_rebuilt = PETSC_FALSE;
  if (!c) PetscFunctionReturn(0);
  PetscCall(MBCContactUpdate(c, s->nbodies, s->bodies, PETSC_FALSE, &researched));
  if (researched && s->monitor && c->nsearches > 1) PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " t %-12.6g contact: re-search (global search %" PetscInt_FMT ")\n", s->step, (double)s->time, c->nsearches));
  PetscCall(MBCInterfaceGetPairs(s->iface, &n, &pairs, &changed));
  if (!changed && !s->force_build) { /* force_build: another step size */
    PetscCall(PetscFree(pairs));
    PetscFunctionReturn(0);
  }
  s->force_build     = PETSC_FALSE;
  s->contact_rebuilt = PETSC_TRUE;
  PetscCall(MBCInterfaceSetUp(s->iface, n, pairs)); /* takes pairs */
  PetscCall(MBCSolverCheckpointTrack(s)); /* where the search ran for this H, for a restart */
  PetscCall(MBCInterfaceGetSize(s->iface, NULL, &nmult));
  if (s->monitor) PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " t %-12.6g contact: %" PetscInt_FMT " contact points, %" PetscInt_FMT " multipliers, flexibility matrix rebuilt\n", s->step, (double)s->time, n, nmult));
  PetscFunctionReturn(0);
}

/* The multipliers of the step: du += A^-1 H lambda. */
static PetscErrorCode SolverContactForces(MBCSolver s)
{
  PetscInt      npoints;
  MBCMultiplier mult;
  PetscBool     failed;

  PetscFunctionBegin;
  PetscCall(MBCInterfaceSolve(s->iface, s->step, s->time, s->contact_may_fail, &failed));
  s->step_its += s->iface->mult->its; /* every solve of the step, the failed ones too: the work done */
  if (failed) s->contact_failed = PETSC_TRUE;
  if (s->contact_failed) PetscFunctionReturn(0); /* the step is cut: nothing to count or print */
  if (s->analysis == MBC_ANALYSIS_DYNAMIC) MBCInterfaceContactWork(s->iface, &s->wfriction, &s->wcontact);
  PetscCall(MBCInterfaceGetSize(s->iface, &npoints, NULL));
  PetscCall(MBCInterfaceGetMultiplier(s->iface, &mult));
  if (s->monitor && npoints) PetscCall(MBCSolverMonitorContact(s, mult));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverMonitor(MBCSolver s)
{
  PetscReal umax = 0, e[MBC_NENERGY];
  char      timing[192];

  PetscFunctionBegin;
  PetscCall(MBCSolverMonitorContact(s, NULL)); /* the step's last contact line, with the states the output writes */
  if (s->usermonitor) PetscCall((*s->usermonitor)(s, s->step, s->time, s->monitorctx));
  if (!s->monitor) PetscFunctionReturn(0);
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscReal n;
    Vec       u;
    if (!s->bodies[b]) continue;
    PetscCall(MBCBodyGetDisplacement(s->bodies[b], &u));
    PetscCall(VecNorm(u, NORM_INFINITY, &n));
    umax = PetscMax(umax, n);
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &umax, 1, MPIU_REAL, MPI_MAX, s->comm));
  PetscCall(MBCSolverMonitorTiming(s, timing, sizeof(timing)));
  s->step_its = 0; /* counted again from the next step's first solve */
  if (s->analysis == MBC_ANALYSIS_DYNAMIC) {
    PetscCall(MBCSolverEnergy(s, e));
    PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " t %-12.6g max|u| %-12.6e energy: kinetic %.6e strain %.6e work %.6e damped %.6e friction %.6e contact %.6e total %.6e %s\n", s->step, (double)s->time, (double)umax, (double)e[0], (double)e[1], (double)e[2], (double)e[3], (double)e[4], (double)e[5], (double)(e[0] + e[1] - e[2] + e[3] + e[4] + e[5]), timing));
  } else PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " t %-12.6g max|u| %-12.6e %s\n", s->step, (double)s->time, (double)umax, timing));
  fflush(PETSC_STDOUT); /* a line per step as it happens, also through a pipe (tee, a job log) */
  PetscFunctionReturn(0);
}

/* A displacement beyond ten times the model's extent is no small-strain answer: a load or a
   material far off (E = 1e-300, a pressure of 1e308, mixed units) that would be written as
   results. Collective on the solver's communicator. */
static PetscErrorCode SolverCheckDisplacementSize(MBCSolver s)
{
  PetscReal *ub, box[6], size = 0;
  PetscInt   worst = 0;

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(s->nbodies, &ub));
  for (PetscInt d = 0; d < 3; d++) box[d] = box[3 + d] = PETSC_MIN_REAL; /* -lo, hi */
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody body = s->bodies[b];
    Vec     X, u = NULL;
    DM      dm;
    PetscCall(MBCBodyGetDisplacement(body, &u));
    if (!u) continue;
    PetscCall(MBCBodyGetDM(body, &dm));
    PetscCall(DMGetCoordinates(dm, &X));
    for (PetscInt d = 0; d < 3; d++) {
      PetscReal lo, hi;
      PetscCall(VecStrideMin(X, d, NULL, &lo));
      PetscCall(VecStrideMax(X, d, NULL, &hi));
      box[d]     = PetscMax(box[d], -lo);
      box[3 + d] = PetscMax(box[3 + d], hi);
    }
    PetscCall(VecNorm(u, NORM_INFINITY, &ub[b]));
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, box, 6, MPIU_REAL, MPIU_MAX, s->comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, ub, (PetscMPIInt)s->nbodies, MPIU_REAL, MPIU_MAX, s->comm));
  for (PetscInt d = 0; d < 3; d++) size = PetscMax(size, box[3 + d] + box[d]);
  for (PetscInt b = 0; b < s->nbodies; b++)
    if (ub[b] > ub[worst]) worst = b;
  {
    const PetscReal u = ub[worst];
    PetscCall(PetscFree(ub));
    PetscCheck(u <= 10 * size, s->comm, PETSC_ERR_USER_INPUT, "Scene file %s: at t = %g body '%s' moves by %g, more than ten times the model's extent %g: no small-strain answer (check E, the loads and their units)", s->scene->filename, (double)s->time, s->scene->bodies[worst].name, (double)u, (double)size);
  }
  PetscFunctionReturn(0);
}

/* Static analysis in the incremental form of the dynamic one, without inertia:
   (K + eps diag K) du = F(t) - K u + H lambda, u += du, repeated within a step until the
   out-of-balance force of the last iterate, max|A du|, is below rtol max|K u| (or below the
   rounding of K u, eps |K| |u|, where the bodies only move rigidly). The spring
   eps diag(K) pulls towards the last iterate only, so at convergence it carries no force and
   K u = F + H lambda holds; it makes K regular for a body held only by contact (block 2 of the
   two-block example), whose rigid motion the contact constraints then fix. The test is on
   forces, not on du: a force imbalance f left by the PGS tolerance moves a stabilised body
   rigidly by f / (eps K_ii), a large du that is no error of equilibrium. Without contact or
   stabilisation one iteration is exact. Here: the factorization, D of the initial pairs and the
   check that every body is held. */
static PetscErrorCode SolverStaticBegin(MBCSolver s)
{
  PetscBool stabilized = PETSC_FALSE, floating = PETSC_FALSE, *free;

  PetscFunctionBegin;
  if (s->iface) PetscCall(MBCInterfaceSetTimeStepping(s->iface, s->analysis, 1.0, PETSC_FALSE)); /* no inertia: the contact force of the step is lambda_n+1 */
  PetscCall(PetscCalloc1(s->nbodies, &free));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscBool bstab, bfloat;
    if (!s->bodies[b]) continue;
    PetscCall(MBCBodyStaticBegin(s->bodies[b], s->static_stabilize, &bstab, &bfloat));
    free[b]    = (PetscBool)(bstab || bfloat);
    stabilized = (PetscBool)(stabilized || bstab);
    floating   = (PetscBool)(floating || bfloat);
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &stabilized, 1, MPIU_BOOL, MPI_LOR, s->comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &floating, 1, MPIU_BOOL, MPI_LOR, s->comm));
  /* before anything is factored or D is built from a singular K (which fails first, with a
     message that does not name the body) */
  for (PetscInt b = 0; b < s->nbodies; b++) { /* a body free in some direction must touch a couple */
    PetscBool touches = PETSC_FALSE;
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &free[b], 1, MPIU_BOOL, MPI_LOR, s->comm));
    for (PetscInt i = 0; s->contact && i < s->contact->ncouples && !touches; i++) {
      MBCSurface *side[2] = {&s->contact->couples[i].master, &s->contact->couples[i].slave};
      for (PetscInt k = 0; k < 2; k++)
        for (PetscInt n = 0; n < side[k]->nnodes && !touches; n++) touches = (PetscBool)(side[k]->nbody[n] == b);
    }
    PetscCheck(!free[b] || touches, s->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: body '%s' has no prescribed displacement in some direction and no contact surface to hold it: its static stiffness is singular (rigid-body motion); prescribe it on some surface or run a dynamic analysis", s->scene->filename, s->scene->bodies[b].name);
  }
  PetscCall(PetscFree(free));
  for (PetscInt b = 0; b < s->nbodies; b++)
    if (s->bodies[b]) PetscCall(MBCBodyStaticFactor(s->bodies[b]));
  s->static_stabilized = stabilized;
  s->static_floating   = floating;
  if (s->restarting) PetscFunctionReturn(0); /* H and D come with the checkpoint's state */
  PetscCall(MBCContactSlidingReset(s->contact)); /* small sliding: pairs fixed per stage */
  if (s->istage == 0) PetscCall(SolverContact(s)); /* D of the initial contact pairs */
  else if (s->iface) PetscCall(MBCInterfaceRebuildD(s->iface)); /* D of K, H as the stage before left it */
  PetscFunctionReturn(0);
}

/* Equilibrium at load time s->time from the bodies' current state: iterates the contact search
   and the multipliers until the out-of-balance force is below -mbc_static_rtol. With
   s->contact_may_fail it gives up (s->contact_failed) where it would stop with an error: the
   multiplier solve or -mbc_static_max_it iterations did not converge. */
static PetscErrorCode SolverStaticEquilibrium(MBCSolver s)
{
  const PetscBool stabilized = s->static_stabilized, floating = s->static_floating;
  PetscReal       fmax = 0, kumax = 0, kufloor = 0;

  PetscFunctionBegin;
  s->contact_failed = PETSC_FALSE;
  if (s->iface) PetscCall(MBCInterfaceLoadStepBegin(s->iface));
  for (s->static_its = 1;; s->static_its++) {
    for (PetscInt b = 0; b < s->nbodies; b++)
      if (s->bodies[b]) PetscCall(MBCBodyStaticIncrement(s->bodies[b], s->time));
    if (s->contact) PetscCall(SolverContactForces(s)); /* du += A^-1 H lambda (+ R alpha) */
    if (s->contact_failed) break; /* the caller cuts the step */
    fmax = kumax = kufloor = 0;
    for (PetscInt b = 0; b < s->nbodies; b++) {
      PetscReal n[3];
      if (!s->bodies[b]) continue;
      PetscCall(MBCBodyStaticUpdate(s->bodies[b], s->time, n));
      fmax    = PetscMax(fmax, n[0]);
      kumax   = PetscMax(kumax, n[1]);
      kufloor = PetscMax(kufloor, n[2]);
    }
    {
      PetscReal mx[3] = {fmax, kumax, kufloor};
      PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, mx, 3, MPIU_REAL, MPIU_MAX, s->comm));
      fmax = mx[0], kumax = mx[1], kufloor = mx[2];
    }
    PetscCall(SolverContact(s));
    PetscCall(MBCSolverMonitorContact(s, NULL));
    if (s->monitor && (s->contact || stabilized || floating)) PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " t %-12.6g static iteration %" PetscInt_FMT ": max|A du| %.3e max|K u| %.3e\n", s->step, (double)s->time, s->static_its, (double)fmax, (double)kumax));
    if ((!s->contact && !stabilized && !floating) || fmax <= s->static_rtol * kumax || (fmax <= kufloor && !s->contact_rebuilt)) break; /* new pairs: not yet in balance */
    if (s->static_its == s->static_max_it && s->contact_may_fail) {
      s->contact_failed = PETSC_TRUE; /* the caller cuts the step */
      break;
    }
    PetscCheck(s->static_its < s->static_max_it, s->comm, PETSC_ERR_NOT_CONVERGED, "Static step %" PetscInt_FMT " (t = %g): no equilibrium after %" PetscInt_FMT " iterations (out-of-balance force max|A du| %g > -mbc_static_rtol %g times max|K u| %g); a body held only by contact may be free to slide, lift off or turn (frictionless or slipping contact, or an initial gap)%s", s->step, (double)s->time, s->static_its, (double)fmax, (double)s->static_rtol, (double)kumax, s->iface && s->iface->mult->rtol > s->static_rtol ? "; or -mbc_multiplier_rtol is looser than -mbc_static_rtol" : "");
  }
  PetscFunctionReturn(0);
}

/* The load from t0 (where the bodies are) to t1. A load step that does not converge is done
   again as two of half the load (down to -mbc_dt_min; -mbc_dt_cut 0 turns it off), and says so.
   "No static equilibrium" is not cut: it is the load's verdict, not the solver's. */
static PetscErrorCode SolverStaticAdvance(MBCSolver s, PetscReal t0, PetscReal t1, PetscInt level)
{
  const PetscBool may_fail = (PetscBool)(s->dt_cut && level + 1 < MBC_MAX_CUTS && (t1 - t0) / 2 >= s->dt_min * (1 - 1e-12));

  PetscFunctionBegin;
  for (PetscInt b = 0; may_fail && b < s->nbodies; b++)
    if (s->bodies[b]) PetscCall(MBCBodyStepSave(s->bodies[b]));
  s->time             = t1;
  s->contact_may_fail = may_fail;
  PetscCall(SolverStaticEquilibrium(s));
  s->contact_may_fail = PETSC_FALSE;
  if (!s->contact_failed) PetscFunctionReturn(0);
  s->ncuts++;
  PetscCall(MBCSolverMonitorContact(s, NULL));
  if (s->iface && s->iface->mult->reason < 0) PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " t %-12.6g contact: %s solve %s: the load step from t %g is cut to two\n", s->step, (double)t1, ((PetscObject)s->iface->mult)->type_name, MBCMultiplierConvergedReasonName(s->iface->mult->reason), (double)t0));
  else PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " t %-12.6g static: no equilibrium after %" PetscInt_FMT " iterations: the load step from t %g is cut to two\n", s->step, (double)t1, s->static_its, (double)t0));
  for (PetscInt b = 0; b < s->nbodies; b++)
    if (s->bodies[b]) PetscCall(MBCBodyStepRestore(s->bodies[b]));
  if (s->iface) PetscCall(MBCInterfaceStepAbandon(s->iface)); /* the slip the attempt made */
  s->time = t0;
  PetscCall(SolverContact(s)); /* the search where the step began */
  PetscCall(SolverStaticAdvance(s, t0, (t0 + t1) / 2, level + 1));
  PetscCall(SolverStaticAdvance(s, (t0 + t1) / 2, t1, level + 1));
  PetscFunctionReturn(0);
}

/* Load step s->step. */
static PetscErrorCode SolverStaticStep(MBCSolver s)
{
  const PetscInt k = s->step - s->stages[s->istage].step0;

  PetscFunctionBegin;
  if (s->iface) PetscCall(MBCInterfaceStepBegin(s->iface)); /* the states report the whole step */
  PetscCall(SolverStaticAdvance(s, MBCSolverStageTime(s, k - 1), MBCSolverStageTime(s, k), 0));
  PetscCall(SolverMonitor(s));
  PetscCall(SolverCheckDisplacementSize(s));
  PetscCall(MBCSolverOutputStep(s));
  PetscFunctionReturn(0);
}

/* The integrator's coefficients for a step h of the current stage (solvergenalpha.c). */
static MBCTimeCoefficients Newmark(MBCSolver s, PetscReal h)
{
  return MBCTimeScheme(h, s->beta, s->gamma, s->am, s->af);
}

/* Every body's factor for h = dt / 2^level, and D rebuilt for it (the pairs unchanged). */
static PetscErrorCode SolverDynamicUseLevel(MBCSolver s, PetscInt level)
{
  const MBCTimeCoefficients c = Newmark(s, s->dt / PetscPowInt(2, level));

  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++)
    if (s->bodies[b]) PetscCall(MBCBodyUseStepLevel(s->bodies[b], level, c));
  s->level       = level;
  s->force_build = PETSC_TRUE;
  PetscCall(MBCContactSlidingReset(s->contact)); /* another step: pairs fixed for it afresh */
  PetscCall(SolverContact(s));
  PetscFunctionReturn(0);
}

/* Newmark in incremental form: K~ dU = F(t+dt) - K u + M (a2 v + a3 a) + C (a4 v + a5 a),
   K~ = K + a0 M + a1 C factored once (the paper's form; contact adds B lambda to the right).
   Here: the initial state, K~ factored, step 0 (its monitor line and output). */
static PetscErrorCode SolverDynamicBegin(MBCSolver s)
{
  const PetscReal dt = s->dt;

  PetscFunctionBegin;
  if (s->iface) PetscCall(MBCInterfaceSetTimeStepping(s->iface, s->analysis, MBCTimeContactWeight(s->gamma, s->am, s->af), MBCTimeContactThroughAcceleration(s->af))); /* contact impulse of a step: dt ((1 - theta) lambda_n + theta lambda_n+1) */
  s->wfriction = s->wcontact = 0;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody body = s->bodies[b];
    if (!body) continue;
    PetscCall(MBCBodyDynamicInitialState(body));
    PetscCall(MBCBodyUseStepLevel(body, 0, Newmark(s, dt)));
  }
  s->level = 0;
  s->step  = 0;
  s->time = 0;
  PetscCall(SolverContact(s)); /* D of the initial contact pairs */
  PetscCall(SolverMonitor(s));
  PetscCall(SolverCheckDisplacementSize(s));
  PetscCall(MBCSolverOutputStep(s));
  PetscFunctionReturn(0);
}

/* A dynamic stage after another one goes on from its state: u, the multipliers and the slip as
   they are, the velocities those of the stage before (0 after a static stage) and the
   accelerations the forces at the stage's start give (0 at a static equilibrium; a load the
   stage adds at its start accelerates the bodies). The factors of the stage before's step
   sizes go, D is rebuilt for this stage's K~ with H as it is. */
static PetscErrorCode SolverDynamicStageBegin(MBCSolver s)
{
  const PetscReal dt = s->dt;
  const PetscBool after_static = (PetscBool)(s->stages[s->istage - 1].analysis == MBC_ANALYSIS_STATIC);

  PetscFunctionBegin;
  if (s->iface) PetscCall(MBCInterfaceSetTimeStepping(s->iface, s->analysis, MBCTimeContactWeight(s->gamma, s->am, s->af), MBCTimeContactThroughAcceleration(s->af)));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody body = s->bodies[b];
    if (!body) continue;
    PetscCall(MBCBodyDynamicStageBegin(body, after_static, s->time));
    PetscCall(MBCBodyUseStepLevel(body, 0, Newmark(s, dt)));
  }
  s->level = s->start_level = s->good_steps = 0;
  if (!s->restarting) PetscCall(MBCContactSlidingReset(s->contact)); /* small sliding: pairs fixed per stage */
  if (s->iface) {
    PetscCall(MBCInterfaceRebuildD(s->iface));
    PetscCall(MBCInterfaceMultipliersToBodies(s->iface));
  }
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody body = s->bodies[b];
    Vec     fc   = NULL, u;
    if (!body) continue;
    if (s->iface) {
      PetscCall(MBCBodyGetDisplacement(body, &u));
      PetscCall(VecDuplicate(u, &fc));
      PetscCall(MBCInterfaceBodyForce(s->iface, b, fc));
    }
    PetscCall(MBCBodyAcceleration(body, s->time, fc));
    PetscCall(VecDestroy(&fc));
    if (after_static) PetscCall(MBCBodyWorkStart(body)); /* as at a dynamic run's start */
  }
  PetscFunctionReturn(0);
}

/* The settings of stage i become the current ones. */
static PetscErrorCode SolverStageSet(MBCSolver s, PetscInt i)
{
  const MBCSolverStage *st = &s->stages[i];

  PetscFunctionBegin;
  s->istage   = i;
  s->analysis = st->analysis;
  s->dt       = st->dt;
  s->beta     = st->beta;
  s->gamma    = st->gamma;
  s->am       = st->am;
  s->af       = st->af;
  s->scheme   = st->scheme;
  PetscCall(MBCSolverStageLog(s, i));
  for (PetscInt b = 0; b < s->nbodies; b++)
    if (s->bodies[b]) PetscCall(MBCBodySetStage(s->bodies[b], i));
  PetscFunctionReturn(0);
}

/* A restart in stage i (solvercheckpoint.c): its settings and operators, the factor of the step
   size s->level the checkpoint was at; no state and no D (they come from the checkpoint). */
PetscErrorCode MBCSolverStageResume(MBCSolver s, PetscInt i)
{
  PetscFunctionBegin;
  PetscCall(SolverStageSet(s, i));
  s->restarting = PETSC_TRUE;
  if (s->analysis == MBC_ANALYSIS_STATIC) PetscCall(SolverStaticBegin(s));
  else {
    if (s->iface) PetscCall(MBCInterfaceSetTimeStepping(s->iface, s->analysis, MBCTimeContactWeight(s->gamma, s->am, s->af), MBCTimeContactThroughAcceleration(s->af)));
    for (PetscInt b = 0; b < s->nbodies; b++)
      if (s->bodies[b]) PetscCall(MBCBodyUseStepLevel(s->bodies[b], s->level, Newmark(s, s->dt / PetscPowInt(2, s->level))));
  }
  s->restarting = PETSC_FALSE;
  PetscFunctionReturn(0);
}

/* Stage i > 0 begins where stage i - 1 ended (docs/scene.md, stages). */
static PetscErrorCode SolverStageBegin(MBCSolver s, PetscInt i)
{
  const MBCSolverStage *st = &s->stages[i];

  PetscFunctionBegin;
  PetscCall(SolverStageSet(s, i));
  if (s->monitor) PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " t %-12.6g stage %" PetscInt_FMT " %s: %s, dt %g, to t = %g\n", s->step, (double)s->time, i, s->scene->nstages ? s->scene->stages[i].name : "", MBCAnalysisTypes[st->analysis], (double)st->dt, (double)st->t1));
  if (st->analysis == MBC_ANALYSIS_STATIC) PetscCall(SolverStaticBegin(s));
  else PetscCall(SolverDynamicStageBegin(s));
  PetscFunctionReturn(0);
}

/* One step of c.h ending at s->time (Newmark, HHT or generalized-alpha: solvergenalpha.c); returns
   with s->contact_failed set and the state untouched when the contact solve did not converge. */
static PetscErrorCode SolverDynamicIncrement(MBCSolver s, MBCTimeCoefficients c)
{
  PetscFunctionBegin;
  if (s->iface && c.cf != 0) PetscCall(MBCInterfaceMultipliersToBodies(s->iface)); /* lambda_n: generalized-alpha's force average */
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody   body = s->bodies[b];
    Vec       fc   = NULL, fr = NULL, u;
    PetscReal wr   = 0;
    if (!body) continue;
    if (s->iface && c.cf != 0) {
      PetscCall(MBCBodyGetDisplacement(body, &u));
      PetscCall(VecDuplicate(u, &fc));
      PetscCall(MBCInterfaceBodyForce(s->iface, b, fc));
    }
    if (s->iface) PetscCall(MBCInterfaceGetReleasedStepForce(s->iface, b, &wr, &fr)); /* the points that left the contact set: an open point's force */
    PetscCall(MBCBodyDynamicIncrement(body, s->time, c, fc, wr, fr));
    PetscCall(VecDestroy(&fc));
  }
  if (s->contact) { /* du += A^-1 H lambda */
    PetscCall(SolverContactForces(s));
    if (s->contact_failed) PetscFunctionReturn(0); /* nothing changed: the caller cuts the step */
    PetscCall(MBCInterfaceReleasedStep(s->iface));
  }
  for (PetscInt b = 0; b < s->nbodies; b++)
    if (s->bodies[b]) PetscCall(MBCBodyDynamicUpdate(s->bodies[b], s->time, c));
  PetscFunctionReturn(0);
}

/* Advances by h = dt / 2^level from s->time. A step whose contact solve fails is done again as
   two steps of h / 2 (down to -mbc_dt_min; -mbc_dt_cut 0 turns it off), and says so. */
static PetscErrorCode SolverDynamicAdvance(MBCSolver s, PetscInt level)
{
  const PetscReal t0 = s->time, h = s->dt / PetscPowInt(2, level);

  PetscFunctionBegin;
  if (level != s->level) PetscCall(SolverDynamicUseLevel(s, level));
  s->deepest = PetscMax(s->deepest, level);
  s->time             = t0 + h;
  s->contact_failed   = PETSC_FALSE;
  s->contact_may_fail = (PetscBool)(s->dt_cut && level + 1 < MBC_MAX_CUTS && h / 2 >= s->dt_min * (1 - 1e-12));
  PetscCall(SolverDynamicIncrement(s, Newmark(s, h)));
  s->contact_may_fail = PETSC_FALSE;
  if (!s->contact_failed) {
    if (level) PetscCall(SolverContact(s)); /* the search between the sub-steps */
    PetscFunctionReturn(0);
  }
  s->ncuts++;
  PetscCall(MBCSolverMonitorContact(s, NULL));
  {
    MBCMultiplier mult;
    PetscCall(MBCInterfaceGetMultiplier(s->iface, &mult));
    PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " t %-12.6g contact: %s solve %s at dt %g: the step is cut to two of dt %g\n", s->step, (double)(t0 + h), ((PetscObject)mult)->type_name, MBCMultiplierConvergedReasonName(mult->reason), (double)h, (double)(h / 2)));
  }
  s->time = t0;
  PetscCall(SolverDynamicAdvance(s, level + 1));
  PetscCall(SolverDynamicAdvance(s, level + 1));
  PetscFunctionReturn(0);
}


/* A static start would ignore an initial state (the scene's `initial`, MBCBodySetInitialState):
   refused rather than dropped (-mbc_analysis static on a dynamic scene with one, say). */
static PetscErrorCode SolverCheckNoInitialState(MBCSolver s)
{
  PetscInt given = 0;

  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    PetscBool has = PETSC_FALSE;
    if (s->bodies[b]) PetscCall(MBCBodyHasInitialState(s->bodies[b], &has));
    if (has) given = PetscMax(given, b + 1);
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &given, 1, MPIU_INT, MPI_MAX, s->comm));
  PetscCheck(!given, s->comm, PETSC_ERR_ARG_INCOMP, "Body '%s' has an initial displacement or velocity (scene file %s's `initial`, or MBCBodySetInitialState) but the analysis starts static: initial conditions start a dynamic analysis", s->scene->bodies[given - 1].name, s->scene->filename);
  PetscFunctionReturn(0);
}

/* Time step s->step, as 2^start_level steps of dt / 2^start_level: after a cut the run stays at
   the step that worked (switching back and forth would refactor nothing, the factors are kept,
   but rebuild D each time) and the step grows back by one halving after MBC_GOOD_STEPS steps
   without a cut. */
#define MBC_GOOD_STEPS 3
static PetscErrorCode SolverDynamicStep(MBCSolver s)
{
  const PetscInt  start = s->start_level, n = PetscPowInt(2, start), k = s->step - s->stages[s->istage].step0;
  const PetscReal t0    = MBCSolverStageTime(s, k - 1);

  PetscFunctionBegin;
  if (s->iface) PetscCall(MBCInterfaceStepBegin(s->iface)); /* the states report the whole step */
  s->deepest = start;
  for (PetscInt k = 0; k < n; k++) {
    s->time = t0 + k * (s->dt / n);
    PetscCall(SolverDynamicAdvance(s, start));
  }
  if (s->deepest > start) s->start_level = s->deepest, s->good_steps = 0;
  else if (start > 0 && ++s->good_steps >= MBC_GOOD_STEPS) s->start_level--, s->good_steps = 0;
  s->time = MBCSolverStageTime(s, k); /* not accumulated */
  PetscCall(SolverContact(s));
  PetscCall(SolverMonitor(s));
  PetscCall(SolverCheckDisplacementSize(s));
  PetscCall(MBCSolverOutputStep(s));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverStep(MBCSolver s)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  PetscCheck(s->stage < 2, s->comm, PETSC_ERR_ARG_WRONGSTATE, "Scene file %s: every step is done (%" PetscInt_FMT " steps to t = %g); raise -mbc_final_time for more", s->scene ? s->scene->filename : "(none)", s->nsteps, (double)s->final_time);
  if (s->stage == 0) {
    PetscCall(MBCSolverSetUp(s));
    if (s->contact) {
      s->contact->check_penetration = (PetscBool)!s->search_only; /* the search report shows the gaps (-mbc_contact_view) */
      PetscCall(MBCContactUpdate(s->contact, s->nbodies, s->bodies, PETSC_TRUE, NULL));
      if (s->contact->view) PetscCall(MBCContactView(s->contact, PETSC_VIEWER_STDOUT_(s->comm)));
    }
    if (s->search_only) {
      s->stage = 2;
      PetscFunctionReturn(0);
    }
    if (s->analysis == MBC_ANALYSIS_MODAL) { /* every mode in one call, its own output: solvermodal.c */
      PetscCall(MBCSolverStageLog(s, 0));
      PetscCall(MBCSolverModalSolve(s));
      PetscCall(MBCSolverStageLog(s, -1));
      s->stage = 2;
      PetscFunctionReturn(0);
    }
    PetscCall(MBCSolverOutputOpen(s));
    s->stage = 1;
    if (s->restart[0]) {
      PetscCall(MBCSolverRestart(s));
      s->step_begin = s->step;
      if (s->step == s->nsteps) { /* the checkpoint of the last step: nothing left */
        PetscCall(MBCSolverOutputClose(s));
        PetscCall(MBCSolverStageLog(s, -1));
        s->stage = 2;
        PetscFunctionReturn(0);
      }
    } else {
      PetscCall(MBCSolverStageLog(s, 0));
      PetscCall(MBCSolverUpliftUpdate(s)); /* the dry joints' resultants, for the initial output too */
      if (s->analysis == MBC_ANALYSIS_STATIC) PetscCall(SolverCheckNoInitialState(s));
      if (s->analysis == MBC_ANALYSIS_STATIC) PetscCall(SolverStaticBegin(s));
      else PetscCall(SolverDynamicBegin(s));
    }
  }
  if (s->step == s->stages[s->istage].step0 + s->stages[s->istage].nsteps) PetscCall(SolverStageBegin(s, s->istage + 1));
  s->step++;
  PetscCall(MBCSolverUpliftUpdate(s)); /* the water in the joints as the last step left them open */
  if (s->analysis == MBC_ANALYSIS_STATIC) PetscCall(SolverStaticStep(s));
  else PetscCall(SolverDynamicStep(s));
  if (s->step == s->nsteps) {
    PetscCall(MBCSolverOutputClose(s));
    PetscCall(MBCSolverStageLog(s, -1));
    s->stage = 2;
  }
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverSolve(MBCSolver s)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  PetscCall(MBCSolverSetUp(s));
  while (s->stage < 2) PetscCall(MBCSolverStep(s));
  PetscFunctionReturn(0);
}

/* Steps done, steps of the run, time reached. */
PetscErrorCode MBCSolverGetStep(MBCSolver s, PetscInt *step, PetscInt *nsteps, PetscReal *time)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  if (step) *step = s->stage ? s->step : 0;
  if (nsteps) *nsteps = s->nsteps;
  if (time) *time = s->stage ? s->time : 0;
  PetscFunctionReturn(0);
}

/* monitor(solver, step, time, ctx) after each step (and after the initial state, step 0, of a
   dynamic analysis), on every rank of the solver; one monitor, a new one replaces it. */
PetscErrorCode MBCSolverMonitorSet(MBCSolver s, PetscErrorCode (*monitor)(MBCSolver, PetscInt, PetscReal, void *), void *ctx, PetscErrorCode (*destroy)(void **))
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  if (s->monitordestroy) PetscCall((*s->monitordestroy)(&s->monitorctx));
  s->usermonitor    = monitor;
  s->monitorctx     = ctx;
  s->monitordestroy = destroy;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverGetMultipliers(MBCSolver s, Vec *lambda)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  PetscValidPointer(lambda, 2);
  *lambda = NULL; /* before the first contact build or without couples */
  if (s->iface) PetscCall(MBCInterfaceGetMultipliers(s->iface, lambda));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverGetContactPoints(MBCSolver s, PetscInt *n, const PetscReal *x[], const PetscReal *normal[], const PetscReal *pressure[], const PetscReal *traction[], const PetscReal *slip[], const PetscInt *state[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  *n = s->cpts.n;
  if (x) *x = s->cpts.x;
  if (normal) *normal = s->cpts.nrm;
  if (pressure) *pressure = s->cpts.pressure;
  if (traction) *traction = s->cpts.traction;
  if (slip) *slip = s->cpts.slip;
  if (state) *state = s->cpts.state;
  PetscFunctionReturn(0);
}

/* The bond of each point of the last step's contact points (couple order, every rank): bonded 1
   while it holds, 0 once broken or on an unbonded couple, and the time it broke (NaN if it did
   not); both NULL without bonded couples (a couple's cohesion, docs/dam.md). */
PetscErrorCode MBCSolverGetContactJoints(MBCSolver s, PetscInt *n, const PetscInt *bonded[], const PetscReal *break_time[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  *n = s->cpts.n;
  if (bonded) *bonded = s->cpts.bonded;
  if (break_time) *break_time = s->cpts.tbreak;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverSetOptionsPrefix(MBCSolver s, const char prefix[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  PetscCall(PetscObjectSetOptionsPrefix((PetscObject)s, prefix));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverAppendOptionsPrefix(MBCSolver s, const char prefix[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  PetscCall(PetscObjectAppendOptionsPrefix((PetscObject)s, prefix));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverGetOptionsPrefix(MBCSolver s, const char *prefix[])
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  PetscCall(PetscObjectGetOptionsPrefix((PetscObject)s, prefix));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverGetScene(MBCSolver s, MBCScene *scene)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  *scene = s->scene;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverView(MBCSolver s, PetscViewer viewer)
{
  PetscBool ascii;

  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  if (!viewer) PetscCall(PetscViewerASCIIGetStdout(s->comm, &viewer));
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(0);
  PetscCheck(s->scene, s->comm, PETSC_ERR_ARG_WRONGSTATE, "MBCSolverView: no scene; call MBCSolverSetScene() first");
  PetscCall(PetscObjectPrintClassNamePrefixType((PetscObject)s, viewer));
  PetscCall(MBCSceneView(s->scene, viewer));
  PetscCall(PetscViewerASCIIPrintf(viewer, "%s analysis: dt %g, %" PetscInt_FMT " steps to t = %g\n", MBCAnalysisTypes[s->analysis], (double)s->dt, s->nsteps, (double)s->final_time));
  {
    PetscMPIInt P;
    PetscCallMPI(MPI_Comm_size(s->comm, &P));
    PetscCall(PetscViewerASCIIPrintf(viewer, "decomposition (METIS on the body graph) onto %d ranks: largest rank work (DOFs^4/3, the factor's entries) %.3f of the mean, %g contact faces between bodies on different ranks\n", P, (double)s->decomp_imbalance, (double)s->decomp_cut));
  }
  for (PetscInt b = 0; b < s->nbodies; b++) {
    const PetscInt ndof = 3 * s->scene->bodies[b].num_nodes; /* the displacement: 3 per node (tet10: its midside nodes too) */
    PetscInt       nbc  = 0, element = 0;
    if (s->bodies[b]) {
      MBCElementType et;
      MPI_Comm       bcomm;
      PetscCall(MBCBodyGetPrescribedRows(s->bodies[b], &nbc, NULL));
      PetscCall(MBCBodyGetElement(s->bodies[b], &et, NULL));
      PetscCall(MBCBodyGetComm(s->bodies[b], &bcomm));
      element = (PetscInt)et;
      PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nbc, 1, MPIU_INT, MPI_SUM, bcomm));
    }
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &nbc, 1, MPIU_INT, MPI_MAX, s->comm));
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &element, 1, MPIU_INT, MPI_MAX, s->comm));
    PetscCall(PetscViewerASCIIPrintf(viewer, "  body %s: ranks %d-%d, %" PetscInt_FMT " DOFs, %" PetscInt_FMT " prescribed (element %s)\n", s->scene->bodies[b].name, s->body_first_rank[b], s->body_first_rank[b] + s->body_nranks[b] - 1, ndof, nbc, MBCElementTypes[element]));
    for (PetscInt l = 0; l < s->scene->nloads; l++) { /* what each load amounts to, to check a scene against hand values */
      PetscReal r[7] = {0, 0, 0, 0, 0, 0, 0};
      PetscBool acts = PETSC_FALSE;
      if (s->bodies[b]) PetscCall(MBCBodySceneLoadResultant(s->bodies[b], l, r, &acts));
      r[6] = acts ? 1 : 0;
      PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, r, 7, MPIU_REAL, MPIU_SUM, s->comm));
      if (r[6] > 0) PetscCall(PetscViewerASCIIPrintf(viewer, "    load %" PetscInt_FMT " (%s): resultant %.10e %.10e %.10e, moment about the origin %.10e %.10e %.10e\n", l, MBCLoadKinds[s->scene->loads[l].kind], (double)r[0], (double)r[1], (double)r[2], (double)r[3], (double)r[4], (double)r[5]));
    }
  }
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverGetNumBodies(MBCSolver s, PetscInt *n)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  *n = s->nbodies;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverGetBody(MBCSolver s, PetscInt b, MBCBody *body)
{
  PetscFunctionBegin;
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  PetscCheck(s->setupcalled, s->comm, PETSC_ERR_ARG_WRONGSTATE, "MBCSolverGetBody: the bodies exist after MBCSolverSetUp()");
  PetscCheck(b >= 0 && b < s->nbodies, s->comm, PETSC_ERR_ARG_OUTOFRANGE, "Body %" PetscInt_FMT " out of range [0, %" PetscInt_FMT ")", b, s->nbodies);
  *body = s->bodies[b];
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverDestroy(MBCSolver *solver)
{
  MBCSolver s = *solver;

  PetscFunctionBegin;
  if (!s) PetscFunctionReturn(0);
  PetscValidHeaderSpecific(s, MBC_SOLVER_CLASSID, 1);
  if (--((PetscObject)s)->refct > 0) {
    *solver = NULL;
    PetscFunctionReturn(0);
  }
  if (s->stage == 1) PetscCall(MBCSolverOutputClose(s)); /* stepped part of the way: the files hold what was done */
  /* still open after an error during the run: HDF5 would flush it at exit, after MPI_Finalize */
  if (s->points_csv) fclose(s->points_csv);
  if (s->energy_csv) fclose(s->energy_csv);
  s->points_csv = s->energy_csv = NULL;
  if (s->h5 >= 0) {
    hid_t file = (hid_t)s->h5;
    s->h5      = -1;
    PetscCall(MBCH5FileClose(&file));
  }
  if (s->monitordestroy) PetscCall((*s->monitordestroy)(&s->monitorctx));
  PetscCall(MBCSolverContactPointsFree(s));
  PetscCall(MBCSolverUpliftDestroy(s));

  PetscCall(MBCInterfaceDestroy(&s->iface));
  PetscCall(MBCContactDestroy(&s->contact));
  for (PetscInt b = 0; b < s->nbodies; b++) PetscCall(MBCBodyDestroy(&s->bodies[b]));
  PetscCall(PetscFree(s->bodies));
  PetscCall(PetscFree2(s->body_first_rank, s->body_nranks));
  PetscCall(MBCSolverOutputBodiesClose(s));
  PetscCall(MBCSolverCheckpointFree(s));
  PetscCall(PetscFree4(s->output_times, s->output_npoints, s->output_cuts, s->output_stage));
  PetscCall(MBCSolverStageLog(s, -1));
  PetscCall(PetscFree(s->stages));
  PetscCall(PetscFree(s->points));
  PetscCall(MBCSceneDestroy(&s->scene));
  PetscCall(PetscHeaderDestroy(solver));
  PetscFunctionReturn(0);
}
