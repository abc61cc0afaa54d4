/* Reactions: per prescribed (Dirichlet) surface, the resultant force the supports exert on the
   bodies, a CSV line per step and surface (<output>_reactions.csv). On a prescribed row the
   unconstrained equation of motion gives it: R = K u + M a + C v - F - H lambda (statics:
   R = K u - F - H lambda), summed over the surface's prescribed rows, component by component;
   H lambda there is the contact force landing on a prescribed contact node.
   Engineers check the base shear and the equilibrium with it (sum of R = -(sum of loads) at
   rest). */
#include <mbc/private/solverimpl.h>

/* Surface index (first Dirichlet entry naming it) of each Dirichlet entry. */
static PetscErrorCode ReactionSurfaces(MBCScene scene, PetscInt *first, PetscInt *nsurf)
{
  PetscFunctionBegin;
  *nsurf = 0;
  for (PetscInt d = 0; d < scene->ndirichlet; d++) {
    first[d] = d;
    for (PetscInt e = 0; e < d; e++) {
      PetscBool same;
      PetscCall(PetscStrcmp(scene->dirichlet[d].surface, scene->dirichlet[e].surface, &same));
      if (same) {
        first[d] = first[e];
        break;
      }
    }
    if (first[d] == d) (*nsurf)++;
  }
  PetscFunctionReturn(0);
}

PetscErrorCode MBCSolverOutputReactionsOpen(MBCSolver s)
{
  PetscMPIInt rank;
  char        file[PETSC_MAX_PATH_LEN];

  PetscFunctionBegin;
  PetscCallMPI(MPI_Comm_rank(s->comm, &rank));
  if (!s->scene->ndirichlet || rank || s->analysis == MBC_ANALYSIS_MODAL) PetscFunctionReturn(0); /* a mode shape has no reactions */
  PetscCall(PetscSNPrintf(file, sizeof(file), "%s_reactions.csv", s->output));
  PetscCall(MBCFileOpenWrite(file, &s->reactions_csv));
  fprintf(s->reactions_csv, "t,surface,fx,fy,fz\n");
  PetscFunctionReturn(0);
}

/* f: the contact force on body b's prescribed rows (this rank's), which H leaves out: a
   prescribed DOF takes no contact force, its support does (H's rows are zeroed there). lam: the
   multipliers lambda_n+1 in couple order. Without it a reaction missed the contact force on a
   contact node that is also prescribed (a corner node of a plate on a wall: the contact resultant
   and the reactions disagreed by it). */
static PetscErrorCode BodyPrescribedContactForce(MBCSolver s, PetscInt b, const PetscReal lam[], Vec f)
{
  MBCInterface    ifc  = s->iface;
  MBCBody         body = s->bodies[b];
  MBCContact      c    = s->contact;
  PetscScalar    *fv;
  PetscInt        rstart, nbc;
  const PetscInt *bcrows;

  PetscFunctionBegin;
  PetscCall(VecZeroEntries(f));
  PetscCall(MBCBodyGetPrescribedRows(body, &nbc, &bcrows));
  if (!nbc) PetscFunctionReturn(0);
  PetscCall(VecGetOwnershipRange(f, &rstart, NULL));
  PetscCall(VecGetArray(f, &fv));
  for (PetscInt k = 0; k < ifc->ncontact; k++) {
    const MBCCouple *cp = &c->couples[ifc->kcouple[k]];
    const PetscInt   j = ifc->kpoint[k], o = ifc->coff[k], dim = ifc->coff[k + 1] - o;
    PetscReal        force[3] = {0, 0, 0}; /* the point's multiplier force in global axes, on its master side */
    for (PetscInt a = 0; a < dim; a++)
      for (PetscInt d = 0; d < 3 && !(ifc->held[k] & (1 << a)); d++) force[d] += lam[o + a] * ifc->frames[9 * k + 3 * a + d];
    for (PetscInt side = 0; side < 2; side++) {
      const PetscInt   lo = side ? cp->soff[j] : cp->moff[j], hi = side ? cp->soff[j + 1] : cp->moff[j + 1];
      const PetscInt  *node = side ? cp->snode : cp->mnode;
      const PetscReal *w    = side ? cp->sw : cp->mw;
      const MBCSurface *sf  = side ? &cp->slave : &cp->master;
      for (PetscInt l = lo; l < hi; l++) {
        if (sf->nbody[node[l]] != b) continue;
        for (PetscInt d = 0; d < 3; d++) {
          PetscInt at;
          PetscCall(PetscFindInt(sf->nrow[node[l]] + d, nbc, bcrows, &at));
          if (at >= 0) fv[sf->nrow[node[l]] + d - rstart] += (side ? -w[l] : w[l]) * force[d];
        }
      }
    }
  }
  PetscCall(VecRestoreArray(f, &fv));
  PetscFunctionReturn(0);
}

/* The internal, inertial and damping forces minus the loads and the contact forces, on every
   row of the body (only the prescribed rows are used). */
static PetscErrorCode BodyResidual(MBCSolver s, PetscInt b, const PetscReal lam[], Vec r)
{
  MBCBody body = s->bodies[b];
  Vec     f;

  PetscFunctionBegin;
  PetscCall(VecDuplicate(r, &f));
  PetscCall(MBCBodyPrescribedRowsForce(body, (PetscBool)(s->analysis == MBC_ANALYSIS_DYNAMIC), r));
  PetscCall(MBCBodyExternalForce(body, s->time, PETSC_FALSE, f));
  PetscCall(VecAXPY(r, -1.0, f));
  if (s->iface) { /* H lambda_n+1 of the step (MBCInterfaceMultipliersToBodies) */
    PetscCall(MBCInterfaceBodyForce(s->iface, b, f));
    PetscCall(VecAXPY(r, -1.0, f));
    PetscCall(BodyPrescribedContactForce(s, b, lam, f));
    PetscCall(VecAXPY(r, -1.0, f));
  }
  PetscCall(VecDestroy(&f));
  PetscFunctionReturn(0);
}

/* Collective: every rank sums its prescribed rows, rank 0 writes. */
PetscErrorCode MBCSolverOutputReactionsStep(MBCSolver s)
{
  MBCScene   scene = s->scene;
  PetscInt  *first, nsurf;
  PetscReal *sum, *lam = NULL;

  PetscFunctionBegin;
  if (!scene->ndirichlet || s->analysis == MBC_ANALYSIS_MODAL) PetscFunctionReturn(0);
  PetscCall(PetscMalloc1(scene->ndirichlet, &first));
  PetscCall(PetscCalloc1(3 * scene->ndirichlet, &sum));
  PetscCall(ReactionSurfaces(scene, first, &nsurf));
  if (s->iface) {
    PetscInt m;
    PetscCall(MBCInterfaceMultipliersToBodies(s->iface));
    PetscCall(MBCInterfaceGetSize(s->iface, NULL, &m));
    PetscCall(PetscCalloc1(m + 1, &lam));
    if (m && s->iface->lamprev) PetscCall(MBCInterfaceGather(s->iface, s->iface->lamprev, lam)); /* lambda_n+1, couple order */
  }
  for (PetscInt b = 0; b < s->nbodies; b++) {
    MBCBody            body = s->bodies[b];
    Vec                u, r;
    const PetscScalar *rv;
    PetscInt           rstart, nbc;
    const PetscInt    *bcrows, *bcentry;
    if (!body) continue;
    PetscCall(MBCBodyGetDisplacement(body, &u));
    PetscCall(MBCBodyGetPrescribedRows(body, &nbc, &bcrows));
    PetscCall(MBCBodyGetPrescribedEntries(body, &bcentry));
    PetscCall(VecDuplicate(u, &r));
    PetscCall(BodyResidual(s, b, lam, r));
    PetscCall(VecGetOwnershipRange(r, &rstart, NULL));
    PetscCall(VecGetArrayRead(r, &rv));
    for (PetscInt i = 0; i < nbc; i++) {
      const PetscInt d = bcentry[i];
      if (d < 0) continue; /* an absorbing surface held in a static state (bodyabsorbing.c) */
      sum[3 * first[d] + scene->dirichlet[d].component] += PetscRealPart(rv[bcrows[i] - rstart]);
    }
    PetscCall(VecRestoreArrayRead(r, &rv));
    PetscCall(VecDestroy(&r));
  }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, sum, 3 * (PetscMPIInt)scene->ndirichlet, MPIU_REAL, MPIU_SUM, s->comm));
  if (s->reactions_csv)
    for (PetscInt d = 0; d < scene->ndirichlet; d++)
      if (first[d] == d) fprintf(s->reactions_csv, "%.17g,%s,%.17g,%.17g,%.17g\n", (double)s->time, scene->dirichlet[d].surface, (double)sum[3 * d], (double)sum[3 * d + 1], (double)sum[3 * d + 2]);
  PetscCall(PetscFree(first));
  PetscCall(PetscFree(sum));
  PetscCall(PetscFree(lam));
  PetscFunctionReturn(0);
}
