/* Output: one HDF5 result file <output>.h5, written collectively by all ranks (the bodies'
   geometry and fields in the scene's order, solveroutputbody.c; the contact points,
   solveroutputcontact.c), its XDMF index for ParaView, time histories of named points and
   energies to CSV. */
#include <mbc/private/solverimpl.h>
#include <mbc/private/h5util.h>
#include <errno.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <signal.h>

/* Nearest owned vertex of each output point, over the bodies it may belong to. */
static PetscErrorCode SolverLocatePoints(MBCSolver s)
{
  MBCScene    scene = s->scene;
  PetscMPIInt rank;
  PetscReal  *box; /* per body: -min and max of its reference coordinates */
  struct {
    double d;
    int    rank;
  } *best;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscCalloc1(scene->npoints, &s->points));
  PetscCall(PetscMalloc1(scene->npoints, &best));
  PetscCall(PetscMalloc1(6 * s->nbodies + 1, &box));
  for (PetscInt i = 0; i < 6 * s->nbodies; i++) box[i] = PETSC_MIN_REAL;
  for (PetscInt p = 0; p < scene->npoints; p++) {
    s->points[p].distance = PETSC_MAX_REAL;
    s->points[p].body     = -1;
    s->points[p].row      = -1;
  }
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody            body = s->bodies[b];
    PetscSection       gsec, csec;
    Vec                coords;
    const PetscScalar *x;
    PetscInt           vStart, vEnd;
    DM                 dm;
    const char        *name;
    if (!body) continue;
    PetscCall(MBCBodyGetDM(body, &dm));
    PetscCall(MBCBodyGetName(body, &name));
    PetscCall(DMGetGlobalSection(dm, &gsec));
    PetscCall(DMGetCoordinateSection(dm, &csec));
    PetscCall(DMGetCoordinatesLocal(dm, &coords));
    PetscCall(VecGetArrayRead(coords, &x));
    PetscCall(DMPlexGetDepthStratum(dm, 0, &vStart, &vEnd));
    for (PetscInt v = vStart; v < vEnd; v++) {
      PetscInt off, coff;
      PetscCall(PetscSectionGetOffset(gsec, v, &off));
      if (off < 0) continue;
      PetscCall(PetscSectionGetOffset(csec, v, &coff));
      for (PetscInt c = 0; c < 3; c++) {
        box[6 * b + c]     = PetscMax(box[6 * b + c], -PetscRealPart(x[coff + c]));
        box[6 * b + 3 + c] = PetscMax(box[6 * b + 3 + c], PetscRealPart(x[coff + c]));
      }
      for (PetscInt p = 0; p < scene->npoints; p++) {
        PetscReal d = 0;
        PetscBool same = PETSC_TRUE;
        if (scene->points[p].body[0]) PetscCall(PetscStrcmp(scene->points[p].body, name, &same));
        if (!same) continue;
        for (PetscInt c = 0; c < 3; c++) d += PetscSqr(PetscRealPart(x[coff + c]) - scene->points[p].x[c]);
        d = PetscSqrtReal(d);
        if (d < s->points[p].distance) {
          s->points[p].distance = d;
          s->points[p].body     = b;
          s->points[p].row      = off;
          for (PetscInt c = 0; c < 3; c++) s->points[p].xv[c] = PetscRealPart(x[coff + c]);
        }
      }
    }
    PetscCall(VecRestoreArrayRead(coords, &x));
  }
  for (PetscInt p = 0; p < scene->npoints; p++) {
    best[p].d    = (double)s->points[p].distance;
    best[p].rank = rank;
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, best, (PetscMPIInt)scene->npoints, MPI_DOUBLE_INT, MPI_MINLOC, s->comm));
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, box, (PetscMPIInt)(6 * s->nbodies), MPIU_REAL, MPIU_MAX, s->comm));
  for (PetscInt p = 0; p < scene->npoints; p++) {
    PetscReal size = 0; /* the diagonal of the box of the bodies the point may snap to */
    PetscCheck(best[p].d < 0.5 * PETSC_MAX_REAL, s->comm, PETSC_ERR_ARG_WRONG, "Scene file %s: output point '%s' names body '%s', which does not exist", scene->filename, scene->points[p].name, scene->points[p].body);
    {
      PetscReal lo[3] = {PETSC_MAX_REAL, PETSC_MAX_REAL, PETSC_MAX_REAL}, hi[3] = {PETSC_MIN_REAL, PETSC_MIN_REAL, PETSC_MIN_REAL};
      for (PetscInt b = 0; b < s->nbodies; b++) {
        PetscBool same = PETSC_TRUE;
        if (scene->points[p].body[0]) PetscCall(PetscStrcmp(scene->points[p].body, scene->bodies[b].name, &same));
        for (PetscInt c = 0; same && c < 3; c++) lo[c] = PetscMin(lo[c], -box[6 * b + c]), hi[c] = PetscMax(hi[c], box[6 * b + 3 + c]);
      }
      for (PetscInt c = 0; c < 3; c++) size += PetscSqr(hi[c] - lo[c]);
      size = PetscSqrtReal(size);
    }
    /* a point inside the bodies' box is nearer a vertex than the box's diagonal: one farther off
       was meant elsewhere (another unit, a typo), and its history would be some vertex's */
    PetscCheck(best[p].d <= size, s->comm, PETSC_ERR_USER_INPUT, "Scene file %s: output point '%s' at (%g, %g, %g) lies %g from the nearest vertex of %s%s%s, farther than the size of %s (%g): check its coordinates and their unit", scene->filename, scene->points[p].name, (double)scene->points[p].x[0], (double)scene->points[p].x[1], (double)scene->points[p].x[2], best[p].d, scene->points[p].body[0] ? "body '" : "every body", scene->points[p].body, scene->points[p].body[0] ? "'" : "", scene->points[p].body[0] ? "that body" : "the model", (double)size);
    s->points[p].rank = best[p].rank;
    if (best[p].rank != rank) s->points[p].row = -1;
    PetscCallMPI(MPI_Bcast(s->points[p].xv, 3, MPIU_REAL, best[p].rank, s->comm));
    PetscCallMPI(MPI_Bcast(&s->points[p].body, 1, MPIU_INT, best[p].rank, s->comm));
    s->points[p].distance = best[p].d;
    if (s->view) PetscCall(PetscPrintf(s->comm, "  output point %s at (%g, %g, %g): vertex (%g, %g, %g) of body %s, distance %g\n", scene->points[p].name, (double)scene->points[p].x[0], (double)scene->points[p].x[1], (double)scene->points[p].x[2], (double)s->points[p].xv[0], (double)s->points[p].xv[1], (double)s->points[p].xv[2], scene->bodies[s->points[p].body].name, (double)s->points[p].distance));
  }
  PetscCall(PetscFree(best));
  PetscCall(PetscFree(box));
  PetscFunctionReturn(0);
}

/* A dynamic run's points also report their absolute displacement, velocity and acceleration:
   the bodies' own (relative to the base in the relative-motion form) plus the ground's (0 in a
   scene in absolute motion). */
static PetscBool SolverPointsAbsolute(MBCSolver s)
{
  return (PetscBool)(s->has_dynamic && s->analysis != MBC_ANALYSIS_MODAL);
}

/* The CSV histories are flushed after every step, so that a killed or failed run leaves whole
   lines; a write error (full disk, file-size limit) is found on rank 0 and raised on every rank
   (collective), so that the run stops cleanly. */
static PetscErrorCode SolverFlushCsv(MBCSolver s)
{
  FILE       *fp[4]     = {s->points_csv, s->energy_csv, s->contact_csv, s->reactions_csv};
  const char *suffix[4] = {"_points.csv", "_energy.csv", "_contact.csv", "_reactions.csv"};
  int         bad = -1, err = 0;

  PetscFunctionBegin;
  for (int i = 0; i < 4 && bad < 0; i++)
    if (fp[i] && (fflush(fp[i]) || ferror(fp[i]))) {
      bad = i;
      err = errno;
    }
  {
    int v[2] = {bad, err};
    PetscCallMPI(MPI_Bcast(v, 2, MPI_INT, 0, s->comm));
    bad = v[0], err = v[1];
  }
  PetscCheck(bad < 0, s->comm, PETSC_ERR_FILE_WRITE, "Cannot write %s%s at t = %g: %s (is the disk full, or the file-size limit, ulimit -f, reached?)", s->output, suffix[bad], (double)s->time, strerror(err));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverWriteXdmf(MBCSolver, PetscBool *);

/* Space for the next output step, reserved on disk right after a flush (the flush leaves the
   file at its allocated size): twice the last step's bytes, at least 64 KiB. A full disk or
   the file-size limit (ulimit -f) is then met here, with nothing of the next step allocated,
   and not inside HDF5, which would leave a superblock that claims more than the file holds
   (unreadable: "truncated file"). HDF5 trims the file back at the next flush or at close. */
static PetscErrorCode SolverOutputReserve(MBCSolver s)
{
  PetscMPIInt rank;
  int         err = 0;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  if (!rank) {
    struct stat st;
    int         fd = open(s->h5file, O_WRONLY);
    if (fd < 0 || fstat(fd, &st)) err = errno;
    else {
      off_t step = s->h5_size > 0 ? (off_t)(st.st_size - s->h5_size) : (off_t)st.st_size, want = PetscMax(2 * step, 65536);
      err        = posix_fallocate(fd, st.st_size, want);
      s->h5_size = (PetscInt64)st.st_size;
    }
    if (fd >= 0) close(fd);
  }
  PetscCallMPI(MPI_Bcast(&err, 1, MPI_INT, 0, s->comm));
  PetscCheck(!err, s->comm, PETSC_ERR_FILE_WRITE, "Cannot extend the result file %s for the output step after t = %g: %s (is the disk full, or the file-size limit, ulimit -f, reached?)", s->h5file, (double)s->time, strerror(err));
  PetscFunctionReturn(0);
}

/* Makes the outputs written so far durable: the time of each in /time, their count in
   num_outputs, the file flushed (a reader sees exactly these outputs if the run is killed
   before the next commit; num_outputs, not the groups present, says which are complete), then
   the XDMF index of these outputs replaces the old one atomically. Collective. */
static PetscErrorCode SolverOutputCommit(MBCSolver s)
{
  hid_t       file = (hid_t)s->h5;
  int         n    = (int)s->noutputs;
  PetscMPIInt rank;
  PetscBool   ok = PETSC_TRUE;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(MBCH5WriteRowsGrow(file, "time", H5T_NATIVE_DOUBLE, s->noutputs, PetscMax(s->noutputs - 1, 0), rank || !s->noutputs ? 0 : 1, s->noutputs ? s->output_times + s->noutputs - 1 : NULL));
  PetscCall(MBCH5WriteRowsGrow(file, "cuts", H5T_NATIVE_INT, s->noutputs, PetscMax(s->noutputs - 1, 0), rank || !s->noutputs ? 0 : 1, s->noutputs ? s->output_cuts + s->noutputs - 1 : NULL));
  PetscCall(MBCH5WriteRowsGrow(file, "stage", H5T_NATIVE_INT, s->noutputs, PetscMax(s->noutputs - 1, 0), rank || !s->noutputs ? 0 : 1, s->noutputs ? s->output_stage + s->noutputs - 1 : NULL));
  PetscCall(MBCH5WriteAttribute(file, "num_outputs", H5T_NATIVE_INT, 1, &n));
  PetscCall(MBCH5FileFlush(file));
  if (!rank) PetscCall(SolverWriteXdmf(s, &ok));
  PetscCallMPI(MPI_Bcast(&ok, 1, MPIU_BOOL, 0, s->comm));
  PetscCheck(ok, s->comm, PETSC_ERR_FILE_WRITE, "Cannot write the XDMF index %s.xmf at t = %g (is the disk full, or the file-size limit, ulimit -f, reached?)", s->output, (double)s->time);
  PetscCall(SolverOutputReserve(s));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverOutputOpen(MBCSolver s)
{
  MBCScene    scene  = s->scene;
  PetscBool   fields = (PetscBool)(scene->output_displacement || scene->output_stress || scene->output_envelope);
  PetscMPIInt rank;
  char        file[PETSC_MAX_PATH_LEN];

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_Output, 0, 0, 0, 0));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(PetscTime(&s->t_start));
  s->t_last = s->t_start;
  PetscCall(PetscMalloc4(s->nsteps + 2, &s->output_times, s->nsteps + 2, &s->output_npoints, s->nsteps + 2, &s->output_cuts, s->nsteps + 2, &s->output_stage));
  s->cuts_written = 0;
  s->noutputs = s->xmf_outputs = 0;
  s->h5_size  = 0;
  if (fields || s->contact) {
    hid_t file_id;
    int   version = 2; /* 2: stress in XDMF's Tensor6 order (1: xx yy zz xy yz xz) */
    PetscCall(PetscSNPrintf(s->h5file, sizeof(s->h5file), "%s.h5", s->output));
    PetscCall(MBCH5FileCreate(s->comm, s->h5file, &file_id));
    s->h5 = file_id;
    PetscCall(MBCH5WriteAttributeString(file_id, "format", "mbcontact result"));
    PetscCall(MBCH5WriteAttribute(file_id, "format_version", H5T_NATIVE_INT, 1, &version));
    PetscCall(MBCH5WriteAttributeString(file_id, "title", scene->title));
    if (fields) PetscCall(MBCSolverOutputBodiesOpen(s));
  }
  PetscCall(MBCSolverOutputContactOpen(s));
  if (s->h5 >= 0) PetscCall(SolverOutputCommit(s)); /* geometry and an empty index: readable from the start */
  if (scene->npoints) {
    PetscCall(SolverLocatePoints(s));
    if (!rank) {
      PetscCall(PetscSNPrintf(file, sizeof(file), "%s_points.csv", s->output));
      PetscCall(MBCFileOpenWrite(file, &s->points_csv));
      fprintf(s->points_csv, "t");
      for (PetscInt p = 0; p < scene->npoints; p++) fprintf(s->points_csv, ",%s_ux,%s_uy,%s_uz", scene->points[p].name, scene->points[p].name, scene->points[p].name);
      if (SolverPointsAbsolute(s)) /* the motion engineers report: relative plus the ground's */
        for (PetscInt p = 0; p < scene->npoints; p++)
          for (PetscInt q = 0; q < 3; q++)
            for (PetscInt c = 0; c < 3; c++) fprintf(s->points_csv, ",%s_abs_%c%c", scene->points[p].name, "uva"[q], "xyz"[c]);
      fprintf(s->points_csv, "\n");
    }
  }
  if (scene->output_energy && s->has_dynamic && !rank) { /* written in the dynamic stages */
    PetscCall(PetscSNPrintf(file, sizeof(file), "%s_energy.csv", s->output));
    PetscCall(MBCFileOpenWrite(file, &s->energy_csv));
    fprintf(s->energy_csv, "t,kinetic,strain,external_work,damping_dissipation,friction_dissipation,contact_dissipation,total\n");
  }
  PetscCall(MBCSolverOutputReactionsOpen(s));
  PetscCall(SolverFlushCsv(s));
  PetscCall(PetscLogEventEnd(MBC_Output, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverOutputPoints(MBCSolver s)
{
  MBCScene        scene = s->scene;
  const PetscBool absolute = SolverPointsAbsolute(s);
  const PetscInt  nv = absolute ? 12 : 3; /* u; absolute u, v, a */
  PetscReal      *val, g[9];

  PetscFunctionBegin;
  PetscCall(PetscCalloc1(nv * scene->npoints, &val));
  if (absolute) PetscCall(MBCSceneGroundMotion(scene, s->istage, s->time, &g[0], &g[3], &g[6]));
  for (PetscInt p = 0; p < scene->npoints; p++) {
    Vec      vecs[3];
    PetscInt rstart;
    MBCBody  body;
    if (s->points[p].row < 0) continue;
    body = s->bodies[s->points[p].body];
    PetscCall(MBCBodyGetDisplacement(body, &vecs[0]));
    PetscCall(MBCBodyGetVelocity(body, &vecs[1]));
    PetscCall(MBCBodyGetAcceleration(body, &vecs[2]));
    PetscCall(VecGetOwnershipRange(vecs[0], &rstart, NULL));
    for (PetscInt q = 0; q < (absolute ? 3 : 1); q++) {
      const PetscScalar *x;
      PetscCall(VecGetArrayRead(vecs[q], &x));
      for (PetscInt c = 0; c < 3; c++) {
        const PetscReal xc = PetscRealPart(x[s->points[p].row - rstart + c]);
        if (!q) val[nv * p + c] = xc;
        if (absolute) val[nv * p + 3 + 3 * q + c] = xc + g[3 * q + c];
      }
      PetscCall(VecRestoreArrayRead(vecs[q], &x));
    }
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, val, nv * (PetscMPIInt)scene->npoints, MPIU_REAL, MPI_SUM, s->comm));
  if (s->points_csv) {
    fprintf(s->points_csv, "%.17g", (double)s->time);
    for (PetscInt p = 0; p < scene->npoints; p++)
      for (PetscInt i = 0; i < 3; i++) fprintf(s->points_csv, ",%.17g", (double)val[nv * p + i]);
    for (PetscInt p = 0; absolute && p < scene->npoints; p++)
      for (PetscInt i = 3; i < 12; i++) fprintf(s->points_csv, ",%.17g", (double)val[nv * p + i]);
    fprintf(s->points_csv, "\n");
  }
  PetscCall(PetscFree(val));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverOutputStep(MBCSolver s)
{
  MBCScene              scene = s->scene;
  PetscBool             fields = (PetscBool)(scene->output_displacement || scene->output_stress || scene->output_envelope);
  const MBCSolverStage *st = &s->stages[s->istage];
  PetscBool             fieldstep = (PetscBool)((fields || s->contact) && (s->step % s->output_every == 0 || s->step == st->step0 + st->nsteps)); /* and each stage's end */
  int                   sig;

  PetscFunctionBegin;
  PetscCall(MBCStopSignalled(s->comm, &sig)); /* between steps: a signal makes this the last one, written whole */
  if (sig && (fields || s->contact)) fieldstep = PETSC_TRUE;
  PetscCall(PetscLogEventBegin(MBC_Output, 0, 0, 0, 0));
  if (scene->npoints) PetscCall(SolverOutputPoints(s));
  if (scene->output_envelope && s->analysis != MBC_ANALYSIS_MODAL)
    for (PetscInt b = 0; b < s->nbodies; b++)
      if (s->bodies[b]) PetscCall(MBCBodyEnvelopeUpdate(s->bodies[b], s->time));
  if (scene->output_energy && s->analysis == MBC_ANALYSIS_DYNAMIC) {
    PetscReal e[MBC_NENERGY];
    PetscCall(MBCSolverEnergy(s, e));
    if (s->energy_csv) fprintf(s->energy_csv, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", (double)s->time, (double)e[0], (double)e[1], (double)e[2], (double)e[3], (double)e[4], (double)e[5], (double)(e[0] + e[1] - e[2] + e[3] + e[4] + e[5]));
  }
  PetscCall(MBCSolverOutputContactStep(s, fieldstep));
  PetscCall(MBCSolverOutputReactionsStep(s));
  if (fieldstep) {
    if (fields) PetscCall(MBCSolverOutputBodiesStep(s));
    if (!s->contact) s->output_npoints[s->noutputs] = 0;
    s->output_cuts[s->noutputs]  = (int)(s->ncuts - s->cuts_written);
    s->output_stage[s->noutputs] = (int)s->istage;
    s->cuts_written             = s->ncuts;
    s->output_times[s->noutputs++] = s->time;
    PetscCall(SolverOutputCommit(s));
  }
  PetscCall(SolverFlushCsv(s));
  PetscCall(PetscLogEventEnd(MBC_Output, 0, 0, 0, 0));
  if (s->step > 0 && (sig || (s->checkpoint_every && s->step % s->checkpoint_every == 0))) PetscCall(MBCSolverCheckpointWrite(s));
  PetscCheck(!sig, s->comm, PETSC_ERR_SIG, "Stopped by signal %d (%s) after step %" PetscInt_FMT " of %" PetscInt_FMT " (t = %g): %" PetscInt_FMT " output steps (the last at t = %g) are in %s.h5, indexed by %s.xmf, and the CSV histories are complete to t = %g; -mbc_restart %s_checkpoint.h5 goes on from there", sig, sig == SIGINT ? "SIGINT" : (sig == SIGTERM ? "SIGTERM" : "?"), s->step, s->nsteps, (double)s->time, s->noutputs, s->noutputs ? (double)s->output_times[s->noutputs - 1] : 0.0, s->output, s->output, (double)s->time, s->output);
  PetscFunctionReturn(0);
}

/* The XDMF index: a temporal collection of spatial collections (a grid per body, one for the
   contact points), every dataset in the one result file. Written beside it and renamed over it,
   so that a reader (or a kill) never meets half an index. The outputs already indexed are
   copied from the old index, not formatted again (the index grows by ~1 KB per body and
   output). Rank 0; *ok false on a write error. */
static const char XdmfTail[] = "  </Grid>\n  </Domain>\n</Xdmf>\n";

static PetscErrorCode SolverWriteXdmf(MBCSolver s, PetscBool *ok)
{
  char     file[PETSC_MAX_PATH_LEN], part[PETSC_MAX_PATH_LEN + 8];
  FILE    *fp, *old = NULL;
  PetscInt first = 0;

  PetscFunctionBegin;
  PetscCall(PetscSNPrintf(file, sizeof(file), "%s.xmf", s->output));
  PetscCall(PetscSNPrintf(part, sizeof(part), "%s.part", file));
  *ok = PETSC_FALSE;
  if (!(fp = fopen(part, "w"))) PetscFunctionReturn(0);
  if (s->xmf_outputs > 0 && (old = fopen(file, "r")) && !fseek(old, 0, SEEK_END)) {
    long keep = ftell(old) - (long)strlen(XdmfTail); /* all but the closing tags */
    char buf[65536];
    rewind(old);
    while (keep > 0) {
      size_t n = fread(buf, 1, (size_t)PetscMin(keep, (long)sizeof(buf)), old);
      if (!n || fwrite(buf, 1, n, fp) != n) break;
      keep -= (long)n;
    }
    if (!keep) first = s->xmf_outputs;
  }
  if (old) fclose(old);
  if (s->xmf_outputs > 0 && !first) { /* could not copy: write it all */
    fclose(fp);
    if (!(fp = fopen(part, "w"))) PetscFunctionReturn(0);
  }
  if (!first) {
    fprintf(fp, "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"2.0\">\n  <Domain>\n");
    fprintf(fp, "  <Grid Name=\"mbcontact\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
  }
  for (PetscInt k = first; k < s->noutputs; k++) {
    fprintf(fp, "    <Grid Name=\"step%" PetscInt_FMT "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n      <Time Value=\"%.17g\"/>\n", k, (double)s->output_times[k]);
    PetscCall(MBCSolverOutputBodiesXdmf(s, fp, k));
    PetscCall(MBCSolverOutputContactXdmf(s, fp, k));
    fprintf(fp, "    </Grid>\n");
  }
  fputs(XdmfTail, fp);
  *ok = (PetscBool)!ferror(fp);
  if (fclose(fp)) *ok = PETSC_FALSE;
  if (*ok && rename(part, file)) *ok = PETSC_FALSE;
  if (!*ok) remove(part);
  else s->xmf_outputs = s->noutputs;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverOutputClose(MBCSolver s)
{
  PetscMPIInt rank;

  PetscFunctionBegin;
  PetscCall(PetscLogEventBegin(MBC_Output, 0, 0, 0, 0));
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCall(MBCSolverOutputContactClose(s));
  if (s->points_csv) fclose(s->points_csv);
  if (s->energy_csv) fclose(s->energy_csv);
  if (s->reactions_csv) fclose(s->reactions_csv);
  s->points_csv = s->energy_csv = s->reactions_csv = NULL;
  if (s->h5 >= 0) { /* /time, num_outputs and the XDMF index are up to date (SolverOutputCommit) */
    hid_t file = (hid_t)s->h5;
    PetscCall(MBCH5FileClose(&file));
    s->h5 = -1;
  }
  PetscCall(MBCSolverOutputBodiesClose(s));
  PetscCall(PetscLogEventEnd(MBC_Output, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* After an error: close the CSV files (this rank's own; their lines are complete) and leave
   the result file to HDF5, which closes it at MPI_Finalize (not at all if the job is aborted):
   it holds every committed output step either way: the failed step's allocations lie within
   the space reserved after the last commit (SolverOutputReserve; if the step needs no more than
   twice the last one), so that close never claims more than the file holds. Not collective;
   never raises an error. */
PetscErrorCode MBCSolverOutputAbort(MBCSolver s)
{
  if (!s) return 0;
  if (s->log_pushed) PetscLogStagePop(); /* -log_view of the stages so far */
  s->log_pushed = PETSC_FALSE;
  if (s->points_csv) fclose(s->points_csv);
  if (s->energy_csv) fclose(s->energy_csv);
  if (s->contact_csv) fclose(s->contact_csv);
  if (s->reactions_csv) fclose(s->reactions_csv);
  s->points_csv = s->energy_csv = s->contact_csv = s->reactions_csv = NULL;
  s->h5 = -1;
  return 0;
}
