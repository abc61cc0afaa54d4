/* Contact points on prescribed nodes (docs/design.md, "Prescribed contact nodes"): a direction
   both sides are held in carries no multiplier, whatever the plane's orientation to the point's
   frame; a master node prescribed on its side only is named in a warning. */
#include <mbc/private/interfaceimpl.h>

/* Per node of every couple's sides (master nodes of couple i from off[2 i], slave nodes from
   off[2 i + 1]): bit d set where its DOF d is prescribed. The bodies know their prescribed rows
   where they own them: OR-ed over the ranks. Collective. */
static PetscErrorCode NodePrescribed(MBCInterface ifc, PetscInt **mask, PetscInt **off)
{
  MBCContact c = ifc->contact;

  PetscFunctionBegin;
  PetscCall(PetscMalloc1(2 * c->ncouples + 1, off));
  (*off)[0] = 0;
  for (PetscInt i = 0; i < c->ncouples; i++) {
    (*off)[2 * i + 1] = (*off)[2 * i] + c->couples[i].master.nnodes;
    (*off)[2 * i + 2] = (*off)[2 * i + 1] + c->couples[i].slave.nnodes;
  }
  PetscCall(PetscCalloc1((*off)[2 * c->ncouples] + 1, mask));
  for (PetscInt i = 0; i < c->ncouples; i++)
    for (PetscInt side = 0; side < 2; side++) {
      const MBCSurface *s = side ? &c->couples[i].slave : &c->couples[i].master;
      for (PetscInt v = 0; v < s->nnodes; v++) {
        const MBCBody   body = ifc->bodies[s->nbody[v]];
        PetscInt        nbc  = 0;
        const PetscInt *bcrows = NULL;
        if (body) PetscCall(MBCBodyGetPrescribedRows(body, &nbc, &bcrows));
        for (PetscInt d = 0; body && d < 3; d++) {
          PetscInt at;
          PetscCall(PetscFindInt(s->nrow[v] + d, nbc, bcrows, &at));
          if (at >= 0) (*mask)[(*off)[2 * i + side] + v] |= 1 << d;
        }
      }
    }
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, *mask, (PetscMPIInt)(*off)[2 * c->ncouples], MPIU_INT, MPI_BOR, ifc->comm));
  PetscFunctionReturn(0);
}

/* After the frames of a new build are set, before H: ifc->held[k], bit a set where direction a
   (0 n, 1 t1, 2 t2) of point k carries no multiplier (H gets no column entries there, so W's row
   is 0 and the multiplier types give it none), and the frame turned so that such a direction is
   one of its tangents. An axis is held at a point where its master node is prescribed along it
   and so is every slave node of its constraint on the plane through the master node normal to
   the axis (at least one): a symmetry plane, or rollers on both sides. The relative motion along
   the axis is then prescribed; with the integrated constraint the point's slave weights also
   reach nodes off that plane, which a multiplier there would push against the prescribed master
   node, a traction across a symmetry plane that symmetry makes 0 (a sphere sheared along such a
   plane: |q_y| up to 0.99 mu p). Frictionless points have no tangents: nothing is held there.
   A master node prescribed along an axis its constraint's other nodes are not, where the point's
   multipliers have a component along it, is counted for the warning (its contact force along the
   axis goes into the support, not into the body); named at the first build. Collective. */
PetscErrorCode MBCInterfaceHeldDirections(MBCInterface ifc)
{
  MBCContact c = ifc->contact;
  PetscInt  *mask, *off, nwarn = 0;
  char       list[1024] = "";

  PetscFunctionBegin;
  PetscCall(PetscFree(ifc->held));
  PetscCall(PetscCalloc1(ifc->ncontact + 1, &ifc->held));
  if (!ifc->ncontact) PetscFunctionReturn(0);
  PetscCall(NodePrescribed(ifc, &mask, &off));
  for (PetscInt k = 0; k < ifc->ncontact; k++) {
    const PetscInt   i = ifc->kcouple[k], j = ifc->kpoint[k], dim = ifc->coff[k + 1] - ifc->coff[k];
    const MBCCouple *cp = &c->couples[i];
    const PetscInt   M = cp->points[j].master, mm = mask[off[2 * i] + M];
    PetscReal       *n = &ifc->frames[9 * k], *t1 = n + 3, *t2 = n + 6, h[2][3];
    PetscInt         nh = 0, oneside = 0;
    if (!mm) continue;
    for (PetscInt a = 0; a < 3; a++) {
      PetscInt  onplane = 0;
      PetscBool both    = PETSC_TRUE;
      if (!(mm & (1 << a))) continue;
      for (PetscInt l = cp->soff[j]; l < cp->soff[j + 1]; l++) {
        const PetscInt s = cp->snode[l];
        if (cp->sw[l] == 0 || PetscAbsReal(cp->slave.x0[3 * s + a] - cp->master.x0[3 * M + a]) > 1e-6 * cp->h) continue;
        onplane++;
        if (!(mask[off[2 * i + 1] + s] & (1 << a))) both = PETSC_FALSE;
      }
      if (onplane && both) {
        PetscReal t[3] = {-n[a] * n[0], -n[a] * n[1], -n[a] * n[2]}, len;
        t[a] += 1; /* the axis' tangential part: held where the axis lies mostly in the tangent plane */
        if (dim < 3 || MBCDot(t, t) < 0.25) continue;
        for (PetscInt q = 0; q < nh; q++) {
          const PetscReal p = MBCDot(t, h[q]);
          for (PetscInt e = 0; e < 3; e++) t[e] -= p * h[q][e];
        }
        len = MBCNormalize(t);
        if (len > 1e-6 && nh < 2) PetscCall(PetscArraycpy(h[nh++], t, 3));
      } else if (PetscAbsReal(n[a]) > 1e-8 || (dim == 3 && 1 - n[a] * n[a] > 1e-8)) oneside |= 1 << a;
    }
    if (nh == 1) { /* t2 along the held direction, t1 = t2 x n */
      PetscCall(PetscArraycpy(t2, h[0], 3));
      MBCCross(t2, n, t1);
      MBCNormalize(t1);
      ifc->held[k] = 1 << 2;
    } else if (nh == 2) ifc->held[k] = (1 << 1) | (1 << 2);
    if (oneside && !ifc->held_warned) {
      if (nwarn < 5) {
        char one[256];
        PetscCall(PetscSNPrintf(one, sizeof(one), "%s couple k = %" PetscInt_FMT ", node (%g, %g, %g) of body '%s' (%s%s%s prescribed)", nwarn ? ";" : "", cp->k, (double)cp->master.x0[3 * M], (double)cp->master.x0[3 * M + 1], (double)cp->master.x0[3 * M + 2], ifc->scene->bodies[cp->master.nbody[M]].name, oneside & 1 ? "x" : "", oneside & 2 ? "y" : "", oneside & 4 ? "z" : ""));
        PetscCall(PetscStrlcat(list, one, sizeof(list)));
      }
      nwarn++;
    }
  }
  if (nwarn) PetscCall(PetscPrintf(ifc->comm, "mbcontact: warning: %" PetscInt_FMT " contact points lie on master nodes prescribed on their side only:%s%s. Their contact force along the prescribed direction goes into the support instead of the body; take such nodes out of contact with the couple's `exclude` key (docs/scene.md)\n", nwarn, list, nwarn > 5 ? "; ..." : ""));
  ifc->held_warned = PETSC_TRUE;
  PetscCall(PetscFree(mask));
  PetscCall(PetscFree(off));
  PetscFunctionReturn(0);
}
