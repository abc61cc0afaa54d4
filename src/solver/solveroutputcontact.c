/* Contact output: per step, a CSV line per couple (points in each state, resultant force); at
   the field output steps, every contact point's position, pressure, tangential traction, force,
   state and gap in <output>_contact.h5 (rank 0, HDF5 C API), shown by the XDMF index as points. */
#include <mbc/private/solverimpl.h>
#include <mbc/private/h5util.h>

PetscErrorCode MBCSolverOutputContactOpen(MBCSolver s)
{
  PetscMPIInt rank;
  char        file[PETSC_MAX_PATH_LEN];

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  if (!s->contact || rank) PetscFunctionReturn(0);
  PetscCall(PetscSNPrintf(file, sizeof(file), "%s_contact.csv", s->output));
  PetscCall(MBCFileOpenWrite(file, &s->contact_csv));
  fprintf(s->contact_csv, "t,couple,points,separated,stick,slip,normal_force,fx,fy,fz,max_slip,max_opening\n");
  PetscCall(PetscSNPrintf(file, sizeof(file), "%s_contact.h5", s->output));
  H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
  s->contact_h5 = H5Fcreate(file, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  PetscCheck(s->contact_h5 >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot create the contact result file %s", file);
  PetscFunctionReturn(0);
}

/* fields: also write the points to the HDF5 file as output number s->noutputs. The data are
   replicated on every rank; rank 0 writes. */
PetscErrorCode MBCSolverOutputContactStep(MBCSolver s, PetscBool fields)
{
  MBCContact c = s->contact;
  PetscInt   np = 0, count[3], *state;
  PetscReal *lam, *x, *x0, *slip, *nrm, *force, *pressure, *traction, *gap, *area;
  int       *couple, *istate;

  PetscFunctionBegin;
  if (!c || (!s->contact_csv && !s->contact_h5)) PetscFunctionReturn(0);
  for (PetscInt i = 0; i < c->ncouples; i++) np += c->couples[i].npoints;
  PetscCall(PetscCalloc6(3 * np + 1, &lam, 3 * np + 1, &x, 3 * np + 1, &nrm, 3 * np + 1, &force, 3 * np + 1, &traction, np + 1, &state));
  PetscCall(PetscCalloc5(np + 1, &pressure, np + 1, &gap, np + 1, &area, np + 1, &couple, np + 1, &istate));
  PetscCall(PetscCalloc2(3 * np + 1, &x0, 3 * np + 1, &slip));
  if (np == s->ncontact) PetscCall(MBCSolverContactStates(s, count, state, lam)); /* else: no forces yet */
  for (PetscInt i = 0, k = 0; i < c->ncouples; i++) {
    MBCCouple *cp = &c->couples[i];
    PetscReal  sum[5] = {0, 0, 0, 0, 0}; /* -, the three states, normal force */
    PetscReal  f[3]   = {0, 0, 0}, maxslip = 0, maxopen = 0;
    PetscInt   kfirst = k;
    for (PetscInt j = 0; j < cp->npoints; j++, k++) {
      const MBCContactPoint *p = &cp->points[j];
      const PetscReal       *z = &lam[3 * k];
      couple[k] = (int)cp->k;
      istate[k] = (int)state[k];
      gap[k]    = cp->igap[j];
      area[k]   = p->area;
      for (PetscInt d = 0; d < 3; d++) {
        x[3 * k + d]        = cp->master.x[3 * p->master + d];
        x0[3 * k + d]       = cp->master.x0[3 * p->master + d];
        nrm[3 * k + d]      = p->n[d];
        force[3 * k + d]    = z[0] * p->n[d] + z[1] * p->t1[d] + z[2] * p->t2[d];
        traction[3 * k + d] = area[k] > 0 ? (z[1] * p->t1[d] + z[2] * p->t2[d]) / area[k] : 0;
        slip[3 * k + d]     = cp->mu > 0 && np == s->ncontact ? s->slip[3 * k + 1] * p->t1[d] + s->slip[3 * k + 2] * p->t2[d] : (cp->mu > 0 ? 0 : NAN);
        f[d] += force[3 * k + d];
      }
      maxslip = PetscMax(maxslip, PetscSqrtReal(PetscSqr(slip[3 * k]) + PetscSqr(slip[3 * k + 1]) + PetscSqr(slip[3 * k + 2])));
      maxopen = PetscMax(maxopen, gap[k]);
      pressure[k] = area[k] > 0 ? z[0] / area[k] : 0;
      sum[1 + state[k]] += 1;
      sum[4] += z[0];
    }
    if (cp->mu == 0) maxslip = NAN; /* frictionless: the tangential motion is not tracked */
    if (s->contact_csv) fprintf(s->contact_csv, "%.17g,%" PetscInt_FMT ",%" PetscInt_FMT ",%d,%d,%d,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n", (double)s->time, cp->k, k - kfirst, (int)sum[1], (int)sum[2], (int)sum[3], (double)sum[4], (double)f[0], (double)f[1], (double)f[2], (double)maxslip, (double)maxopen);
  }
  if (fields && s->contact_h5 >= 0 && s->contact_csv) {
    char  name[64];
    hid_t g, sp, at;
    PetscCall(PetscSNPrintf(name, sizeof(name), "step_%" PetscInt_FMT, s->noutputs));
    g  = H5Gcreate2(s->contact_h5, name, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    sp = H5Screate(H5S_SCALAR);
    at = H5Acreate2(g, "time", H5T_NATIVE_DOUBLE, sp, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(at, H5T_NATIVE_DOUBLE, &s->time);
    H5Aclose(at);
    H5Sclose(sp);
    PetscCall(MBCH5WriteArray(g, "position", H5T_NATIVE_DOUBLE, np, 3, x));
    PetscCall(MBCH5WriteArray(g, "reference", H5T_NATIVE_DOUBLE, np, 3, x0));
    PetscCall(MBCH5WriteArray(g, "normal", H5T_NATIVE_DOUBLE, np, 3, nrm));
    PetscCall(MBCH5WriteArray(g, "force", H5T_NATIVE_DOUBLE, np, 3, force));
    PetscCall(MBCH5WriteArray(g, "multiplier", H5T_NATIVE_DOUBLE, np, 3, lam));
    PetscCall(MBCH5WriteArray(g, "pressure", H5T_NATIVE_DOUBLE, np, 1, pressure));
    PetscCall(MBCH5WriteArray(g, "traction", H5T_NATIVE_DOUBLE, np, 3, traction));
    PetscCall(MBCH5WriteArray(g, "gap", H5T_NATIVE_DOUBLE, np, 1, gap));
    PetscCall(MBCH5WriteArray(g, "slip", H5T_NATIVE_DOUBLE, np, 3, slip));
    PetscCall(MBCH5WriteArray(g, "area", H5T_NATIVE_DOUBLE, np, 1, area));
    PetscCall(MBCH5WriteArray(g, "state", H5T_NATIVE_INT, np, 1, istate));
    PetscCall(MBCH5WriteArray(g, "couple", H5T_NATIVE_INT, np, 1, couple));
    H5Gclose(g);
  }
  PetscCall(PetscFree6(lam, x, nrm, force, traction, state));
  PetscCall(PetscFree5(pressure, gap, area, couple, istate));
  PetscCall(PetscFree2(x0, slip));
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverOutputContactClose(MBCSolver s)
{
  PetscFunctionBegin;
  if (s->contact_csv) fclose(s->contact_csv);
  s->contact_csv = NULL;
  if (s->contact_h5 >= 0) H5Fclose(s->contact_h5);
  s->contact_h5 = -1;
  PetscFunctionReturn(0);
}

/* The contact points of output k as an XDMF polyvertex grid (called by rank 0). */
PetscErrorCode MBCSolverOutputContactXdmf(MBCSolver s, FILE *fp, PetscInt k)
{
  char        h5name[PETSC_MAX_PATH_LEN], h5path[PETSC_MAX_PATH_LEN], path[64];
  const char *base = s->output, *slash;
  const char *scalars[3] = {"pressure", "gap", "state"}, *vectors[4] = {"traction", "force", "normal", "slip"};
  hid_t       h5;
  hsize_t     np = 0;

  PetscFunctionBegin;
  if (!s->contact) PetscFunctionReturn(0);
  if ((slash = strrchr(s->output, '/'))) base = slash + 1;
  PetscCall(PetscSNPrintf(h5name, sizeof(h5name), "%s_contact.h5", base));
  PetscCall(PetscSNPrintf(h5path, sizeof(h5path), "%s_contact.h5", s->output));
  PetscCall(PetscSNPrintf(path, sizeof(path), "step_%" PetscInt_FMT, k));
  h5 = H5Fopen(h5path, H5F_ACC_RDONLY, H5P_DEFAULT);
  PetscCheck(h5 >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot reopen %s", h5path);
  if (H5Lexists(h5, path, H5P_DEFAULT) > 0) {
    hid_t d, sp;
    PetscCall(PetscStrlcat(path, "/pressure", sizeof(path)));
    d  = H5Dopen2(h5, path, H5P_DEFAULT);
    sp = H5Dget_space(d);
    H5Sget_simple_extent_dims(sp, &np, NULL);
    H5Sclose(sp);
    H5Dclose(d);
  }
  H5Fclose(h5);
  if (!np) PetscFunctionReturn(0);
  fprintf(fp, "      <Grid Name=\"contact\" GridType=\"Uniform\">\n");
  fprintf(fp, "        <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%llu\" NodesPerElement=\"1\"/>\n", (unsigned long long)np);
  fprintf(fp, "        <Geometry GeometryType=\"XYZ\">\n          <DataItem Dimensions=\"%llu 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/step_%" PetscInt_FMT "/position</DataItem>\n        </Geometry>\n", (unsigned long long)np, h5name, k);
  for (int i = 0; i < 3; i++) fprintf(fp, "        <Attribute Name=\"%s\" AttributeType=\"Scalar\" Center=\"Node\">\n          <DataItem Dimensions=\"%llu\" NumberType=\"%s\" Precision=\"%d\" Format=\"HDF\">%s:/step_%" PetscInt_FMT "/%s</DataItem>\n        </Attribute>\n", scalars[i], (unsigned long long)np, i == 2 ? "Int" : "Float", i == 2 ? 4 : 8, h5name, k, scalars[i]);
  for (int i = 0; i < 4; i++) fprintf(fp, "        <Attribute Name=\"%s\" AttributeType=\"Vector\" Center=\"Node\">\n          <DataItem Dimensions=\"%llu 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">%s:/step_%" PetscInt_FMT "/%s</DataItem>\n        </Attribute>\n", vectors[i], (unsigned long long)np, h5name, k, vectors[i]);
  fprintf(fp, "      </Grid>\n");
  PetscFunctionReturn(0);
}
