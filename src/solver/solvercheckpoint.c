/* Checkpoint and restart (docs/scene.md, Checkpoint and restart): the whole state of a run after a
   step, written through PETSc's HDF5 viewer to <output>_checkpoint.h5 (beside it, then renamed
   over it), in the scene's order (vertices as in the result file, contact points in couple order),
   so that a run restarts from it on any rank count. A restart rebuilds H and D as they were: the
   contact search is replayed at the displacements it ran at (the global search H used, H's
   build, the last global search, the current state), which gives the same contact points and
   weights, so the restarted run repeats the uninterrupted one to rounding. */
#include <mbc/private/solverimpl.h>
#include <petscviewerhdf5.h>
#include <errno.h>
#include <string.h>

#define MBC_CHECKPOINT_VERSION 1

/* Copies of u at H's build and at the global search it used (the replay's displacements);
   after every MBCInterfaceSetUp. */
PetscErrorCode MBCSolverCheckpointTrack(MBCSolver s)
{
  PetscFunctionBegin;
  if (!s->ubuild) PetscCall(PetscCalloc2(s->nbodies, &s->ubuild, s->nbodies, &s->ugsbuild));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    Vec u;
    if (!s->bodies[b]) continue;
    PetscCall(MBCBodyGetDisplacement(s->bodies[b], &u));
    if (!s->ubuild[b]) PetscCall(VecDuplicate(u, &s->ubuild[b]));
    if (!s->ugsbuild[b]) PetscCall(VecDuplicate(u, &s->ugsbuild[b]));
    PetscCall(VecCopy(u, s->ubuild[b]));
    if (s->contact->usearch[b]) PetscCall(VecCopy(s->contact->usearch[b], s->ugsbuild[b]));
    else PetscCall(VecZeroEntries(s->ugsbuild[b]));
  }
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverCheckpointFree(MBCSolver s)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; s->ubuild && b < s->nbodies; b++) {
    PetscCall(VecDestroy(&s->ubuild[b]));
    PetscCall(VecDestroy(&s->ugsbuild[b]));
  }
  PetscCall(PetscFree2(s->ubuild, s->ugsbuild));
  for (PetscInt b = 0; s->ckpt && b < s->nbodies; b++) {
    PetscCall(PetscSFDestroy(&s->ckpt[b].vsf));
    PetscCall(PetscFree(s->ckpt[b].vrow));
  }
  PetscCall(PetscFree(s->ckpt));
  PetscFunctionReturn(0);
}

/* Every body's vertex map, once. */
static PetscErrorCode CheckpointMaps(MBCSolver s)
{
  PetscFunctionBegin;
  if (s->ckpt) PetscFunctionReturn(0);
  PetscCall(PetscCalloc1(s->nbodies, &s->ckpt));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    s->ckpt[b].nv = s->scene->bodies[b].num_nodes;
    if (s->bodies[b]) PetscCall(MBCBodyVertexMapCreate(s->bodies[b], &s->ckpt[b], NULL, NULL));
  }
  PetscFunctionReturn(0);
}

/* Body b's x (a displacement-layout Vec, NULL off the body) as dataset `name` of the viewer's
   current group, in the scene's vertex order; or read back (load). Collective on the solver. */
static PetscErrorCode CheckpointBodyVec(MBCSolver s, PetscViewer viewer, PetscInt b, Vec x, const char name[], PetscBool load)
{
  MBCBodyOutput *o    = &s->ckpt[b];
  MBCBody        body = s->bodies[b];
  Vec            g;
  PetscScalar   *ga, *xa, *leaf = NULL;

  PetscFunctionBegin;
  PetscCall(VecCreateMPI(s->comm, body ? 3 * o->nvrows : 0, 3 * o->nv, &g));
  PetscCall(PetscObjectSetName((PetscObject)g, name));
  if (load) PetscCall(VecLoad(g, viewer));
  if (body) {
    PetscCall(PetscMalloc1(3 * o->nvown + 1, &leaf));
    PetscCall(VecGetArray(g, &ga));
    PetscCall(VecGetArray(x, &xa));
    if (load) {
      PetscCall(PetscSFBcastBegin(o->vsf, MPIU_SCALAR, ga, leaf, MPI_REPLACE));
      PetscCall(PetscSFBcastEnd(o->vsf, MPIU_SCALAR, ga, leaf, MPI_REPLACE));
      for (PetscInt i = 0; i < o->nvown; i++)
        for (PetscInt c = 0; c < 3; c++) xa[o->vrow[i] + c] = leaf[3 * i + c];
    } else {
      for (PetscInt i = 0; i < o->nvown; i++)
        for (PetscInt c = 0; c < 3; c++) leaf[3 * i + c] = xa[o->vrow[i] + c];
      PetscCall(PetscSFReduceBegin(o->vsf, MPIU_SCALAR, leaf, ga, MPI_REPLACE));
      PetscCall(PetscSFReduceEnd(o->vsf, MPIU_SCALAR, leaf, ga, MPI_REPLACE));
    }
    PetscCall(VecRestoreArray(x, &xa));
    PetscCall(VecRestoreArray(g, &ga));
    PetscCall(PetscFree(leaf));
  }
  if (!load) PetscCall(VecView(g, viewer));
  PetscCall(VecDestroy(&g));
  PetscFunctionReturn(0);
}

/* n reals, the same on every rank, as dataset `name` (held by rank 0); or read back. */
static PetscErrorCode CheckpointArray(MBCSolver s, PetscViewer viewer, PetscInt n, PetscReal a[], const char name[], PetscBool load)
{
  PetscMPIInt  rank;
  Vec          g;
  PetscScalar *ga;

  PetscFunctionBegin;
  if (!n) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(VecCreateMPI(s->comm, rank ? 0 : n, n, &g));
  PetscCall(PetscObjectSetName((PetscObject)g, name));
  PetscCall(VecGetArray(g, &ga));
  if (load) {
    PetscCall(VecRestoreArray(g, &ga));
    PetscCall(VecLoad(g, viewer));
    PetscCall(VecGetArray(g, &ga));
    if (!rank)
      for (PetscInt i = 0; i < n; i++) a[i] = PetscRealPart(ga[i]);
    PetscCallMPI(MPI_Bcast(a, (PetscMPIInt)n, MPIU_REAL, 0, s->comm));
  } else if (!rank)
    for (PetscInt i = 0; i < n; i++) ga[i] = a[i];
  PetscCall(VecRestoreArray(g, &ga));
  if (!load) PetscCall(VecView(g, viewer));
  PetscCall(VecDestroy(&g));
  PetscFunctionReturn(0);
}

/* The scalars of the run's state, in one array (the same on every rank). */
#define MBC_CKPT_NSCALARS 12
static void CheckpointScalars(MBCSolver s, PetscReal v[], PetscBool load)
{
  PetscReal *f[MBC_CKPT_NSCALARS] = {NULL, &s->time, NULL, NULL, NULL, NULL, NULL, &s->wfriction, &s->wcontact, NULL, NULL, &s->dt};
  PetscInt  *i[MBC_CKPT_NSCALARS] = {&s->step, NULL, &s->istage, &s->level, &s->start_level, &s->good_steps, &s->ncuts, NULL, NULL, s->contact ? &s->contact->nsearches : NULL, &s->nsteps, NULL};

  for (PetscInt k = 0; k < MBC_CKPT_NSCALARS; k++) {
    if (load) {
      if (f[k]) *f[k] = v[k];
      else if (i[k] && k != 10 && k != 9) *i[k] = (PetscInt)v[k]; /* nsteps (10) is the run's, checked; nsearches (9) after the replay */
    } else v[k] = f[k] ? *f[k] : (i[k] ? (PetscReal)*i[k] : 0);
  }
}

/* Per body wext and wdamp (the first rank of a body knows them), on every rank. */
static PetscErrorCode CheckpointBodyEnergies(MBCSolver s, PetscReal e[], PetscBool load)
{
  PetscFunctionBegin;
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody     body = s->bodies[b];
    PetscMPIInt brank = 1;
    MPI_Comm    bcomm;
    if (body) {
      PetscCall(MBCBodyGetComm(body, &bcomm));
      PetscCallMPI(MPI_Comm_rank(bcomm, &brank));
    }
    if (load) {
      if (body) PetscCall(MBCBodySetWork(body, e[2 * b], e[2 * b + 1]));
    } else {
      e[2 * b] = e[2 * b + 1] = 0;
      if (!brank) PetscCall(MBCBodyGetWork(body, &e[2 * b], &e[2 * b + 1]));
    }
  }
  if (!load) PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, e, 2 * (PetscMPIInt)s->nbodies, MPIU_REAL, MPI_SUM, s->comm));
  PetscFunctionReturn(0);
}

/* The checkpoint of the state after step s->step: <output>_checkpoint.h5, written as .part and
   renamed over the last one (a kill while writing leaves the last whole checkpoint). Collective. */
PetscErrorCode MBCSolverCheckpointWrite(MBCSolver s)
{
  char        file[PETSC_MAX_PATH_LEN], part[PETSC_MAX_PATH_LEN + 8];
  PetscViewer v;
  PetscReal   sc[MBC_CKPT_NSCALARS], *e;
  PetscInt    nc = 0, m = 0, version = MBC_CHECKPOINT_VERSION;
  PetscMPIInt rank;
  int         err = 0;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_Output, 0, 0, 0, 0));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(CheckpointMaps(s));
  PetscCall(PetscSNPrintf(file, sizeof(file), "%s_checkpoint.h5", s->output));
  PetscCall(PetscSNPrintf(part, sizeof(part), "%s.part", file));
  PetscCall(PetscViewerHDF5Open(s->comm, part, FILE_MODE_WRITE, &v));
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/", "format", PETSC_STRING, "mbcontact checkpoint"));
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/", "format_version", PETSC_INT, &version));
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/", "scene", PETSC_STRING, s->scene->filename));
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/", "num_bodies", PETSC_INT, &s->nbodies));
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/", "num_stages", PETSC_INT, &s->scene->nstages));
  CheckpointScalars(s, sc, PETSC_FALSE);
  PetscCall(CheckpointArray(s, v, MBC_CKPT_NSCALARS, sc, "state", PETSC_FALSE));
  PetscCall(PetscMalloc1(2 * s->nbodies, &e));
  PetscCall(CheckpointBodyEnergies(s, e, PETSC_FALSE));
  PetscCall(CheckpointArray(s, v, 2 * s->nbodies, e, "energies", PETSC_FALSE));
  PetscCall(PetscFree(e));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody body = s->bodies[b];
    Vec     u, vel, acc;
    char    group[MBC_NAME_LEN + 16];
    PetscCall(MBCBodyGetDisplacement(body, &u));
    PetscCall(MBCBodyGetVelocity(body, &vel));
    PetscCall(MBCBodyGetAcceleration(body, &acc));
    PetscCall(PetscSNPrintf(group, sizeof(group), "/bodies/%s", s->scene->bodies[b].name));
    PetscCall(PetscViewerHDF5PushGroup(v, group));
    PetscCall(CheckpointBodyVec(s, v, b, u, "u", PETSC_FALSE));
    PetscCall(PetscViewerHDF5WriteAttribute(v, group, "num_vertices", PETSC_INT, &s->scene->bodies[b].num_vertices));
    if (s->has_dynamic) {
      PetscCall(CheckpointBodyVec(s, v, b, vel, "v", PETSC_FALSE));
      PetscCall(CheckpointBodyVec(s, v, b, acc, "a", PETSC_FALSE));
      if (s->iface) {
        Vec f = NULL;
        if (body) PetscCall(MBCInterfaceGetReleasedForce(s->iface, b, &f));
        PetscCall(CheckpointBodyVec(s, v, b, f, "contact_force_released", PETSC_FALSE));
      }
    }
    if (s->ubuild) {
      PetscCall(CheckpointBodyVec(s, v, b, body ? s->ubuild[b] : NULL, "u_build", PETSC_FALSE));
      PetscCall(CheckpointBodyVec(s, v, b, body ? s->ugsbuild[b] : NULL, "u_search_build", PETSC_FALSE));
      PetscCall(CheckpointBodyVec(s, v, b, body ? s->contact->usearch[b] : NULL, "u_search", PETSC_FALSE));
    }
    PetscCall(PetscViewerHDF5PopGroup(v));
  }
  if (s->iface && s->ubuild) {
    const PetscReal *r, *slip;
    const PetscInt  *pairs;
    PetscReal       *lam, *pr;
    PetscCall(MBCInterfaceGetState(s->iface, &nc, &m, NULL, NULL, NULL, NULL));
    PetscCall(PetscMalloc2(m + 1, &lam, MBC_PAIR_SIZE * nc + 1, &pr));
    PetscCall(MBCInterfaceGetState(s->iface, &nc, &m, lam, &r, &slip, &pairs));
    for (PetscInt i = 0; i < MBC_PAIR_SIZE * nc; i++) pr[i] = (PetscReal)pairs[i];
    PetscCall(PetscViewerHDF5PushGroup(v, "/contact"));
    PetscCall(CheckpointArray(s, v, m, lam, "lambda", PETSC_FALSE));
    PetscCall(CheckpointArray(s, v, m, (PetscReal *)r, "warm_start", PETSC_FALSE));
    PetscCall(CheckpointArray(s, v, 3 * nc, (PetscReal *)slip, "slip", PETSC_FALSE));
    PetscCall(CheckpointArray(s, v, MBC_PAIR_SIZE * nc, pr, "pairs", PETSC_FALSE));
    { /* the multiplier solve's own (the Newton type's kept inverse's reference, its count) */
      PetscBool  has;
      PetscReal *st;
      PetscCall(PetscMalloc1(m + 1, &st));
      PetscCall(MBCInterfaceGetSolveState(s->iface, st, &has));
      if (has) PetscCall(CheckpointArray(s, v, m + 1, st, "solve_state", PETSC_FALSE));
      PetscCall(PetscFree(st));
    }
    PetscCall(PetscViewerHDF5PopGroup(v));
    PetscCall(PetscFree2(lam, pr));
  }
  if (MBCInterfaceHasJoints(s->iface)) { /* the bonded couples' break times per master node (interfacejoint.c) */
    PetscInt   nj;
    PetscReal *tj;
    PetscCall(MBCInterfaceJointGetState(s->iface, &nj, NULL));
    PetscCall(PetscMalloc1(nj + 1, &tj));
    PetscCall(MBCInterfaceJointGetState(s->iface, &nj, tj));
    PetscCall(PetscViewerHDF5PushGroup(v, "/joints"));
    PetscCall(CheckpointArray(s, v, nj, tj, "break_time", PETSC_FALSE));
    PetscCall(PetscViewerHDF5PopGroup(v));
    PetscCall(PetscFree(tj));
  }
  { /* the wet lengths of the joints the next step takes */
    PetscInt         nw;
    const PetscReal *w;
    PetscCall(MBCSolverUpliftNext(s, &nw, &w));
    if (nw) {
      PetscCall(PetscViewerHDF5PushGroup(v, "/uplift"));
      PetscCall(CheckpointArray(s, v, nw, (PetscReal *)w, "wet_length", PETSC_FALSE));
      PetscCall(PetscViewerHDF5PopGroup(v));
    }
  }
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/", "num_points", PETSC_INT, &nc));
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/", "num_multipliers", PETSC_INT, &m));
  PetscCall(PetscViewerDestroy(&v));
  if (!rank && rename(part, file)) err = errno;
  PetscCallMPI(MPI_Bcast(&err, 1, MPI_INT, 0, s->comm));
  PetscCheck(!err, s->comm, PETSC_ERR_FILE_WRITE, "Cannot rename the checkpoint %s to %s: %s", part, file, strerror(err));
  if (s->monitor) PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " t %-12.6g checkpoint %s\n", s->step, (double)s->time, file));
  PetscCall(PetscLogEventEnd(MBC_Output, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* The run goes on from checkpoint s->restart (-mbc_restart): the stage set up as it was, the
   state read, the contact search replayed and H and D built for the same pairs. The outputs of
   the steps after it go to a new result file (s->output was given "_restart"). Collective. */
PetscErrorCode MBCSolverRestart(MBCSolver s)
{
  const char *file = s->restart;
  PetscViewer v;
  PetscReal   sc[MBC_CKPT_NSCALARS], *e;
  PetscInt    version = 0, nb = 0, nst = -1, nc = 0, m = 0, nsearches;
  char       *format = NULL;
  PetscBool   has;

  PetscFunctionBegin;
  PetscCheck(!s->scene->nabsorbing, s->comm, PETSC_ERR_SUP, "Restart file -mbc_restart %s: a scene with absorbing boundaries (%s) cannot be restarted yet (the released supports' reactions are not in the checkpoint); run it from the start", file, s->scene->filename);
  PetscCall(PetscTestFile(file, 'r', &has));
  PetscCheck(has, s->comm, PETSC_ERR_FILE_OPEN, "Restart file -mbc_restart %s does not exist or cannot be read", file);
  PetscCall(PetscViewerHDF5Open(s->comm, file, FILE_MODE_READ, &v));
  PetscCall(PetscViewerHDF5HasAttribute(v, "/", "format", &has));
  if (has) PetscCall(PetscViewerHDF5ReadAttribute(v, "/", "format", PETSC_STRING, NULL, &format));
  PetscCheck(has && !strcmp(format, "mbcontact checkpoint"), s->comm, PETSC_ERR_FILE_UNEXPECTED, "Restart file -mbc_restart %s is not an mbcontact checkpoint (write one with -mbc_checkpoint_every N)", file);
  PetscCall(PetscFree(format));
  PetscCall(PetscViewerHDF5ReadAttribute(v, "/", "format_version", PETSC_INT, NULL, &version));
  PetscCheck(version == MBC_CHECKPOINT_VERSION, s->comm, PETSC_ERR_FILE_UNEXPECTED, "Restart file %s has checkpoint version %" PetscInt_FMT "; this mbcontact reads version %d", file, version, MBC_CHECKPOINT_VERSION);
  PetscCall(PetscViewerHDF5ReadAttribute(v, "/", "scene", PETSC_STRING, NULL, &format));
  PetscCall(PetscViewerHDF5ReadAttribute(v, "/", "num_bodies", PETSC_INT, NULL, &nb));
  PetscCall(PetscViewerHDF5ReadAttribute(v, "/", "num_stages", PETSC_INT, NULL, &nst));
  PetscCall(PetscViewerHDF5ReadAttribute(v, "/", "num_points", PETSC_INT, NULL, &nc));
  PetscCall(PetscViewerHDF5ReadAttribute(v, "/", "num_multipliers", PETSC_INT, NULL, &m));
  PetscCheck(nb == s->nbodies && nst == s->scene->nstages, s->comm, PETSC_ERR_ARG_INCOMP, "Restart file %s was written for another scene (%s: %" PetscInt_FMT " bodies, %" PetscInt_FMT " stages), not scene %s (%" PetscInt_FMT " bodies, %" PetscInt_FMT " stages)", file, format, nb, nst, s->scene->filename, s->nbodies, s->scene->nstages);
  for (PetscInt b = 0; b < s->nbodies; b++) {
    char group[MBC_NAME_LEN + 16];
    PetscCall(PetscSNPrintf(group, sizeof(group), "/bodies/%s", s->scene->bodies[b].name));
    PetscCall(PetscViewerHDF5HasGroup(v, group, &has));
    if (has) PetscCall(PetscViewerHDF5ReadAttribute(v, group, "num_vertices", PETSC_INT, NULL, &nb));
    PetscCheck(has, s->comm, PETSC_ERR_ARG_INCOMP, "Restart file %s was written for another scene (%s): it has no body '%s' of scene %s", file, format, s->scene->bodies[b].name, s->scene->filename);
    PetscCheck(nb == s->scene->bodies[b].num_vertices, s->comm, PETSC_ERR_ARG_INCOMP, "Restart file %s was written for another scene (%s): body '%s' has %" PetscInt_FMT " vertices there, %" PetscInt_FMT " in scene %s", file, format, s->scene->bodies[b].name, nb, s->scene->bodies[b].num_vertices, s->scene->filename);
  }
  PetscCall(PetscFree(format));
  PetscCall(CheckpointMaps(s));
  PetscCall(CheckpointArray(s, v, MBC_CKPT_NSCALARS, sc, "state", PETSC_TRUE));
  PetscCheck((PetscInt)sc[0] <= s->nsteps && (PetscInt)sc[2] < s->nstages, s->comm, PETSC_ERR_ARG_INCOMP, "Restart file %s holds step %" PetscInt_FMT " (stage %" PetscInt_FMT "), beyond this run's %" PetscInt_FMT " steps (raise -mbc_final_time)", file, (PetscInt)sc[0], (PetscInt)sc[2], s->nsteps);
  CheckpointScalars(s, sc, PETSC_TRUE);
  nsearches = (PetscInt)sc[9];
  PetscCheck(s->dt == s->stages[s->istage].dt, s->comm, PETSC_ERR_ARG_INCOMP, "Restart file %s was written with step %g in stage %" PetscInt_FMT ", this run has %g (-mbc_dt)", file, (double)s->dt, s->istage, (double)s->stages[s->istage].dt);
  PetscCall(MBCSolverStageResume(s, s->istage));
  PetscCall(PetscMalloc1(2 * s->nbodies, &e));
  PetscCall(CheckpointArray(s, v, 2 * s->nbodies, e, "energies", PETSC_TRUE));
  PetscCall(CheckpointBodyEnergies(s, e, PETSC_TRUE));
  PetscCall(PetscFree(e));
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody body = s->bodies[b];
    Vec     u, vel, acc;
    char    group[MBC_NAME_LEN + 16];
    PetscCall(MBCBodyGetDisplacement(body, &u));
    PetscCall(MBCBodyGetVelocity(body, &vel));
    PetscCall(MBCBodyGetAcceleration(body, &acc));
    PetscCall(PetscSNPrintf(group, sizeof(group), "/bodies/%s", s->scene->bodies[b].name));
    PetscCall(PetscViewerHDF5PushGroup(v, group));
    PetscCall(CheckpointBodyVec(s, v, b, u, "u", PETSC_TRUE));
    if (s->has_dynamic) {
      PetscCall(CheckpointBodyVec(s, v, b, vel, "v", PETSC_TRUE));
      PetscCall(CheckpointBodyVec(s, v, b, acc, "a", PETSC_TRUE));
      if (s->iface) { /* the released contact points' force in a (a checkpoint written before it was kept has none) */
        char      path[MBC_NAME_LEN + 48];
        PetscBool has;
        Vec       f = NULL;
        PetscCall(PetscSNPrintf(path, sizeof(path), "%s/contact_force_released", group));
        PetscCall(PetscViewerHDF5HasDataset(v, path, &has));
        if (body) PetscCall(MBCInterfaceGetReleasedForce(s->iface, b, &f));
        if (has) PetscCall(CheckpointBodyVec(s, v, b, f, "contact_force_released", PETSC_TRUE));
      }
      if (body) PetscCall(MBCBodyRestartLoad(body, s->time)); /* the energies' trapezoidal work */
    }
    PetscCall(PetscViewerHDF5PopGroup(v));
  }
  if (s->contact && nc) { /* the search replayed: H and D as built, then the current state */
    MBCContact c = s->contact;
    Vec       *ucur;
    PetscReal *lam, *r, *slip, *pr;
    PetscInt   n, *pairs;
    PetscBool  changed;
    const char *step[3] = {"u_search_build", "u_build", "u_search"};

    PetscCall(PetscCalloc1(s->nbodies, &ucur));
    for (PetscInt b = 0; b < s->nbodies; b++) {
      Vec u;
      if (!s->bodies[b]) continue;
      PetscCall(MBCBodyGetDisplacement(s->bodies[b], &u));
      PetscCall(VecDuplicate(u, &ucur[b]));
      PetscCall(VecCopy(u, ucur[b]));
    }
    c->check_penetration = PETSC_FALSE; /* a deformed state: its gaps were accepted when it was reached */
    for (PetscInt k = 0; k < 3; k++) {
      for (PetscInt b = 0; b < s->nbodies; b++) {
        char group[MBC_NAME_LEN + 16];
        Vec  u;
        PetscCall(MBCBodyGetDisplacement(s->bodies[b], &u));
        PetscCall(PetscSNPrintf(group, sizeof(group), "/bodies/%s", s->scene->bodies[b].name));
        PetscCall(PetscViewerHDF5PushGroup(v, group));
        PetscCall(CheckpointBodyVec(s, v, b, u, step[k], PETSC_TRUE));
        PetscCall(PetscViewerHDF5PopGroup(v));
      }
      if (k == 1) { /* H's build: its search kept the faces of the pairs it built where they tie (MBCContactSetPreferredFaces), and searching with those pairs' faces preferred finds them again */
        PetscInt *ip;
        PetscCall(PetscMalloc4(m + 1, &lam, m + 1, &r, 3 * nc + 1, &slip, MBC_PAIR_SIZE * nc + 1, &pr));
        PetscCall(PetscViewerHDF5PushGroup(v, "/contact"));
        PetscCall(CheckpointArray(s, v, m, lam, "lambda", PETSC_TRUE));
        PetscCall(CheckpointArray(s, v, m, r, "warm_start", PETSC_TRUE));
        PetscCall(CheckpointArray(s, v, 3 * nc, slip, "slip", PETSC_TRUE));
        PetscCall(CheckpointArray(s, v, MBC_PAIR_SIZE * nc, pr, "pairs", PETSC_TRUE));
        PetscCall(PetscViewerHDF5PopGroup(v));
        PetscCall(PetscMalloc1(MBC_PAIR_SIZE * nc + 1, &ip));
        for (PetscInt i = 0; i < MBC_PAIR_SIZE * nc; i++) ip[i] = (PetscInt)pr[i];
        PetscCall(MBCContactSetPreferredFaces(c, nc, ip, MBC_PAIR_SIZE));
        PetscCall(PetscFree(ip));
      }
      PetscCall(MBCContactUpdate(c, s->nbodies, s->bodies, (PetscBool)(k != 1), NULL));
      if (k == 1) {
        PetscCall(MBCInterfaceGetPairs(s->iface, &n, &pairs, &changed));
        changed = (PetscBool)(n != nc);
        for (PetscInt i = 0; i < MBC_PAIR_SIZE * nc && !changed; i++) changed = (PetscBool)(pairs[i] != (PetscInt)pr[i]);
        PetscCheck(!changed, s->comm, PETSC_ERR_ARG_INCOMP, "Restart file %s: the contact search at its displacements finds %" PetscInt_FMT " contact points, not the %" PetscInt_FMT " it holds (written for another scene, or with other -mbc_contact_* options?)", file, n, nc);
        PetscCall(MBCInterfaceSetUp(s->iface, n, pairs)); /* takes pairs */
        PetscCall(MBCSolverCheckpointTrack(s));
        PetscCall(MBCInterfaceSetState(s->iface, lam, r, slip));
        { /* absent: written before it was kept, or the solve kept none */
          PetscBool has;
          PetscCall(PetscViewerHDF5HasDataset(v, "/contact/solve_state", &has));
          if (has) {
            PetscReal *st;
            PetscCall(PetscMalloc1(m + 1, &st));
            PetscCall(PetscViewerHDF5PushGroup(v, "/contact"));
            PetscCall(CheckpointArray(s, v, m + 1, st, "solve_state", PETSC_TRUE));
            PetscCall(PetscViewerHDF5PopGroup(v));
            PetscCall(MBCInterfaceSetSolveState(s->iface, st));
            PetscCall(PetscFree(st));
          }
        }
        PetscCall(PetscFree4(lam, r, slip, pr));
      }
    }
    for (PetscInt b = 0; b < s->nbodies; b++) {
      Vec u;
      if (!s->bodies[b]) continue;
      PetscCall(MBCBodyGetDisplacement(s->bodies[b], &u));
      PetscCall(VecCopy(ucur[b], u));
    }
    PetscCall(MBCContactUpdate(c, s->nbodies, s->bodies, PETSC_FALSE, NULL));
    for (PetscInt b = 0; b < s->nbodies; b++) PetscCall(VecDestroy(&ucur[b]));
    PetscCall(PetscFree(ucur));
    c->nsearches         = nsearches;
    c->check_penetration = PETSC_TRUE;
  } else if (s->contact) PetscCall(MBCContactUpdate(s->contact, s->nbodies, s->bodies, PETSC_TRUE, NULL));
  if (MBCInterfaceHasJoints(s->iface)) { /* the bonds broken before the checkpoint stay broken */
    PetscBool  hasj;
    PetscInt   nj;
    PetscReal *tj;
    PetscCall(PetscViewerHDF5HasDataset(v, "/joints/break_time", &hasj));
    PetscCheck(hasj, s->comm, PETSC_ERR_FILE_UNEXPECTED, "Restart file %s has no joint state (/joints/break_time) for the scene's bonded couples: written for another scene?", file);
    PetscCall(MBCInterfaceJointGetState(s->iface, &nj, NULL));
    PetscCall(PetscMalloc1(nj + 1, &tj));
    PetscCall(PetscViewerHDF5PushGroup(v, "/joints"));
    PetscCall(CheckpointArray(s, v, nj, tj, "break_time", PETSC_TRUE));
    PetscCall(PetscViewerHDF5PopGroup(v));
    PetscCall(MBCInterfaceJointSetState(s->iface, nj, tj));
    PetscCall(PetscFree(tj));
  }
  PetscCall(PetscViewerHDF5HasDataset(v, "/uplift/wet_length", &has));
  if (has) {
    PetscInt   nw = 0;
    PetscReal *w;
    for (PetscInt i = 0; i < s->scene->ncouples; i++) nw += s->scene->couples[i].uplift.on ? s->scene->couples[i].uplift.nzones : 0;
    PetscCall(PetscMalloc1(nw + 1, &w));
    PetscCall(PetscViewerHDF5PushGroup(v, "/uplift"));
    PetscCall(CheckpointArray(s, v, nw, w, "wet_length", PETSC_TRUE));
    PetscCall(PetscViewerHDF5PopGroup(v));
    PetscCall(MBCSolverUpliftRestore(s, nw, w));
    PetscCall(PetscFree(w));
  }
  PetscCall(PetscViewerDestroy(&v));
  if (s->monitor) PetscCall(PetscPrintf(s->comm, "step %5" PetscInt_FMT " t %-12.6g restarted from %s (stage %" PetscInt_FMT ")\n", s->step, (double)s->time, file, s->istage));
  PetscFunctionReturn(0);
}
