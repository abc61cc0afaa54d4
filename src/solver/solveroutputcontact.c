/* Contact output: per step, a CSV line per couple (points in each state, resultant force); at
   the output steps, every contact point's position, pressure, tangential traction, force, state
   and gap in the group /contact/step_<k> of the result file, shown by the XDMF index as points.
   The points are replicated on every rank (couple order, canonical: the same at any rank count);
   each rank writes a block of them, collectively. */
#include <mbc/private/solverimpl.h>
#include <mbc/private/h5util.h>

PetscErrorCode MBCSolverOutputContactOpen(MBCSolver s)
{
  PetscMPIInt rank;
  char        file[PETSC_MAX_PATH_LEN];

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  if (!s->contact) PetscFunctionReturn(0);
  if (s->h5 >= 0) {
    hid_t g;
    PetscCall(MBCH5GroupCreate((hid_t)s->h5, "contact", PETSC_FALSE, &g));
    PetscCall(MBCH5GroupClose(&g));
  }
  if (rank) PetscFunctionReturn(0);
  PetscCall(PetscSNPrintf(file, sizeof(file), "%s_contact.csv", s->output));
  PetscCall(MBCFileOpenWrite(file, &s->contact_csv));
  fprintf(s->contact_csv, "t,couple,points,separated,stick,slip,normal_force,fx,fy,fz,max_slip,max_opening,uplift,uplift_x,uplift_y,uplift_z,wet_length%s\n", MBCInterfaceHasJoints(s->iface) ? ",bonded" : ""); /* bonded couples: the points whose bond holds */
  PetscFunctionReturn(0);
}

/* Rows of n replicated ones this rank writes: a block in rank order. */
static PetscErrorCode ContactRows(MBCSolver s, PetscInt n, PetscInt *start, PetscInt *count)
{
  PetscMPIInt rank, size;

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  *start = (n * rank) / size;
  *count = (n * (rank + 1)) / size - *start;
  PetscFunctionReturn(0);
}

/* fields: also write the points to the result file as output number s->noutputs (collective). */
PetscErrorCode MBCSolverOutputContactStep(MBCSolver s, PetscBool fields)
{
  MBCContact   c = s->contact;
  MBCInterface ifc = s->iface; /* read through its struct: the frames and the slip of the last build */
  PetscInt     np = 0, count[3], *state;
  PetscReal *lam, *x, *x0, *slip, *nrm, *force, *pressure, *traction, *gap, *area;
  int       *couple, *istate, *bonded = NULL;
  PetscReal *tbreak = NULL;
  PetscInt  *jbonded = NULL; /* bonded, for MBCSolverGetContactJoints */
  PetscReal *damage  = NULL;
  PetscBool  joints = (PetscBool)(c && MBCInterfaceHasJoints(ifc));

  PetscFunctionBegin;
  if (!c) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < c->ncouples; i++) np += c->couples[i].npoints;
  PetscCall(PetscCalloc6(3 * np + 1, &lam, 3 * np + 1, &x, 3 * np + 1, &nrm, 3 * np + 1, &force, 3 * np + 1, &traction, np + 1, &state));
  PetscCall(PetscCalloc5(np + 1, &pressure, np + 1, &gap, np + 1, &area, np + 1, &couple, np + 1, &istate));
  PetscCall(PetscCalloc2(3 * np + 1, &x0, 3 * np + 1, &slip));
  if (joints) { /* tbreak and jbonded are kept for MBCSolverGetContactJoints, bonded (int) is the file's */
    PetscCall(PetscCalloc1(np + 1, &bonded));
    PetscCall(PetscCalloc1(np + 1, &tbreak));
    PetscCall(PetscCalloc1(np + 1, &jbonded));
    if (MBCInterfaceHasSoftening(ifc)) PetscCall(PetscCalloc1(np + 1, &damage)); /* softening couples: the damage of each point */
  }
  if (np == ifc->ncontact) PetscCall(MBCInterfaceStates(ifc, count, state, lam)); /* else: no forces yet */
  for (PetscInt i = 0, k = 0; i < c->ncouples; i++) {
    MBCCouple *cp = &c->couples[i];
    PetscReal  sum[5] = {0, 0, 0, 0, 0}; /* -, the three states, normal force */
    PetscReal  f[3]   = {0, 0, 0}, maxslip = 0, maxopen = 0, up[5];
    PetscInt   kfirst = k;
    PetscInt   nbonded = 0;
    for (PetscInt j = 0; j < cp->npoints; j++, k++) {
      const MBCContactPoint *p = &cp->points[j];
      const PetscReal       *z = &lam[3 * k];
      /* the multipliers and the slip are in the frames D was built with; the search after the
         step has already moved p's frame (its tangents may even have turned by 90 degrees) */
      const PetscBool  built = (PetscBool)(np == ifc->ncontact && ifc->frames);
      const PetscReal *n = built ? &ifc->frames[9 * k] : p->n, *t1 = built ? &ifc->frames[9 * k + 3] : p->t1, *t2 = built ? &ifc->frames[9 * k + 6] : p->t2;
      couple[k] = (int)cp->k;
      istate[k] = (int)state[k];
      gap[k]    = cp->igap[j];
      area[k]   = p->area;
      for (PetscInt d = 0; d < 3; d++) {
        x[3 * k + d]        = cp->master.x[3 * p->master + d];
        x0[3 * k + d]       = cp->master.x0[3 * p->master + d];
        nrm[3 * k + d]      = n[d];
        force[3 * k + d]    = z[0] * n[d] + z[1] * t1[d] + z[2] * t2[d];
        traction[3 * k + d] = area[k] > 0 ? (z[1] * t1[d] + z[2] * t2[d]) / area[k] : 0;
        slip[3 * k + d]     = cp->mu > 0 && np == ifc->ncontact ? ifc->slip[3 * k + 1] * t1[d] + ifc->slip[3 * k + 2] * t2[d] : (cp->mu > 0 ? 0 : NAN);
        f[d] += force[3 * k + d];
      }
      maxslip = PetscMax(maxslip, PetscSqrtReal(PetscSqr(slip[3 * k]) + PetscSqr(slip[3 * k + 1]) + PetscSqr(slip[3 * k + 2])));
      maxopen = PetscMax(maxopen, gap[k]);
      pressure[k] = area[k] > 0 ? z[0] / area[k] : 0;
      if (joints) {
        jbonded[k] = MBCInterfaceJointPoint(ifc, i, j, &tbreak[k]) == 1;
        if (damage) damage[k] = MBCInterfaceJointDamage(ifc, i, j);
        bonded[k]  = (int)jbonded[k];
        nbonded += jbonded[k];
      }
      sum[1 + state[k]] += 1;
      sum[4] += z[0];
    }
    if (cp->mu == 0) maxslip = NAN; /* frictionless: the tangential motion is not tracked */
    for (PetscInt j = 0; j < s->scene->ncouples; j++) /* the uplift on its faces (solveruplift.c) */
      if (s->scene->couples[j].k == cp->k) PetscCall(MBCSolverUpliftResultant(s, j, up));
    if (s->contact_csv) fprintf(s->contact_csv, "%.17g,%" PetscInt_FMT ",%" PetscInt_FMT ",%d,%d,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", (double)s->time, cp->k, k - kfirst, (int)sum[1], (int)sum[2], (int)sum[3], (double)sum[4], (double)f[0], (double)f[1], (double)f[2], (double)maxslip, (double)maxopen, (double)up[0], (double)up[1], (double)up[2], (double)up[3], (double)up[4]);
    if (s->contact_csv && joints) fprintf(s->contact_csv, ",%d", (int)nbonded);
    if (s->contact_csv) fprintf(s->contact_csv, "\n");
  }
  if (fields && s->h5 >= 0) {
    char     name[64];
    hid_t    g;
    PetscInt r0 = 0, nr = 0;
    int      step = (int)s->step;
    PetscCall(PetscSNPrintf(name, sizeof(name), "contact/step_%" PetscInt_FMT, s->noutputs));
    PetscCall(MBCH5GroupCreate((hid_t)s->h5, name, PETSC_FALSE, &g));
    PetscCall(MBCH5WriteAttribute(g, "time", H5T_NATIVE_DOUBLE, 1, &s->time));
    PetscCall(MBCH5WriteAttribute(g, "step", H5T_NATIVE_INT, 1, &step));
    PetscCall(ContactRows(s, np, &r0, &nr));
    PetscCall(MBCH5WriteRows(g, "position", H5T_NATIVE_DOUBLE, np, 3, r0, nr, x + 3 * r0));
    PetscCall(MBCH5WriteRows(g, "reference", H5T_NATIVE_DOUBLE, np, 3, r0, nr, x0 + 3 * r0));
    PetscCall(MBCH5WriteRows(g, "normal", H5T_NATIVE_DOUBLE, np, 3, r0, nr, nrm + 3 * r0));
    PetscCall(MBCH5WriteRows(g, "force", H5T_NATIVE_DOUBLE, np, 3, r0, nr, force + 3 * r0));
    PetscCall(MBCH5WriteRows(g, "multiplier", H5T_NATIVE_DOUBLE, np, 3, r0, nr, lam + 3 * r0));
    PetscCall(MBCH5WriteRows(g, "pressure", H5T_NATIVE_DOUBLE, np, 1, r0, nr, pressure + r0));
    PetscCall(MBCH5WriteRows(g, "traction", H5T_NATIVE_DOUBLE, np, 3, r0, nr, traction + 3 * r0));
    PetscCall(MBCH5WriteRows(g, "gap", H5T_NATIVE_DOUBLE, np, 1, r0, nr, gap + r0));
    PetscCall(MBCH5WriteRows(g, "slip", H5T_NATIVE_DOUBLE, np, 3, r0, nr, slip + 3 * r0));
    PetscCall(MBCH5WriteRows(g, "area", H5T_NATIVE_DOUBLE, np, 1, r0, nr, area + r0));
    PetscCall(MBCH5WriteRows(g, "state", H5T_NATIVE_INT, np, 1, r0, nr, istate + r0));
    PetscCall(MBCH5WriteRows(g, "couple", H5T_NATIVE_INT, np, 1, r0, nr, couple + r0));
    if (joints) { /* bonded couples: per point 1 while its bond holds, and the time it broke (NaN: it did not, or no bond) */
      PetscCall(MBCH5WriteRows(g, "bonded", H5T_NATIVE_INT, np, 1, r0, nr, bonded + r0));
      PetscCall(MBCH5WriteRows(g, "break_time", H5T_NATIVE_DOUBLE, np, 1, r0, nr, tbreak + r0));
      if (damage) PetscCall(MBCH5WriteRows(g, "damage", H5T_NATIVE_DOUBLE, np, 1, r0, nr, damage + r0));
    }
    PetscCall(MBCH5GroupClose(&g));
    s->output_npoints[s->noutputs] = np;
  }
  PetscCall(PetscFree(bonded));
  PetscCall(PetscFree(damage));
  PetscCall(MBCSolverContactPointsFree(s)); /* keep this step's points for MBCSolverGetContactPoints */
  s->cpts.n = np;
  s->cpts.lam = lam, s->cpts.x = x, s->cpts.nrm = nrm, s->cpts.force = force, s->cpts.traction = traction, s->cpts.state = state;
  s->cpts.pressure = pressure, s->cpts.gap = gap, s->cpts.area = area, s->cpts.couple = couple, s->cpts.istate = istate;
  s->cpts.x0 = x0, s->cpts.slip = slip;
  s->cpts.bonded = jbonded, s->cpts.tbreak = tbreak; /* NULL without bonded couples */
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverContactPointsFree(MBCSolver s)
{
  PetscFunctionBegin;
  if (!s->cpts.x) PetscFunctionReturn(0);
  PetscCall(PetscFree6(s->cpts.lam, s->cpts.x, s->cpts.nrm, s->cpts.force, s->cpts.traction, s->cpts.state));
  PetscCall(PetscFree5(s->cpts.pressure, s->cpts.gap, s->cpts.area, s->cpts.couple, s->cpts.istate));
  PetscCall(PetscFree2(s->cpts.x0, s->cpts.slip));
  PetscCall(PetscFree(s->cpts.tbreak));
  PetscCall(PetscFree(s->cpts.bonded));
  s->cpts.n = 0;
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverOutputContactClose(MBCSolver s)
{
  PetscFunctionBegin;
  if (s->contact_csv) fclose(s->contact_csv);
  s->contact_csv = NULL;
  PetscFunctionReturn(0);
}

/* The contact points of output k as an XDMF polyvertex grid (rank 0). */
PetscErrorCode MBCSolverOutputContactXdmf(MBCSolver s, FILE *fp, PetscInt k)
{
  const char *h5 = strrchr(s->h5file, '/') ? strrchr(s->h5file, '/') + 1 : s->h5file;
  const char *scalars[3] = {"pressure", "gap", "state"}, *vectors[4] = {"traction", "force", "normal", "slip"};
  PetscInt    np;

  PetscFunctionBegin;
  if (!s->contact || !(np = s->output_npoints[k])) PetscFunctionReturn(0);
  fprintf(fp, "      <Grid Name=\"contact\" GridType=\"Uniform\">\n");
  fprintf(fp, "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%" PetscInt_FMT "\" NodesPerElement=\"1\"/>\n", np);
  fprintf(fp, "        <Geometry GeometryType=\"XYZ\">\n          <DataItem Dimensions=\"%" PetscInt_FMT " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/contact/step_%" PetscInt_FMT "/position</DataItem>\n        </Geometry>\n", np, h5, k);
  for (int i = 0; i < 3; i++) fprintf(fp, "        <Attribute Name=\"%s\" AttributeType=\"Scalar\" Center=\"Node\">\n          <DataItem Dimensions=\"%" PetscInt_FMT "\" NumberType=\"%s\" Precision=\"%d\" Format=\"HDF\">%s:/contact/step_%" PetscInt_FMT "/%s</DataItem>\n        </Attribute>\n", scalars[i], np, i == 2 ? "Int" : "Float", i == 2 ? 4 : 8, h5, k, scalars[i]);
  for (int i = 0; i < 4; i++) fprintf(fp, "        <Attribute Name=\"%s\" AttributeType=\"Vector\" Center=\"Node\">\n          <DataItem Dimensions=\"%" PetscInt_FMT " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/contact/step_%" PetscInt_FMT "/%s</DataItem>\n        </Attribute>\n", vectors[i], np, h5, k, vectors[i]);
  fprintf(fp, "      </Grid>\n");
  PetscFunctionReturn(0);
}
