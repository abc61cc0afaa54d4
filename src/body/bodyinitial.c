/* Initial conditions of a dynamic analysis: a displacement and a velocity per node, from the scene
   (`initial:`, docs/scene.md) or set from the API before the first step (MBCBodySetInitialState,
   Python's Body.setInitialState), which wins over the scene's. The dynamic start takes them instead
   of the static equilibrium under the constant loads (displacement) and rest (velocity). */
#include <mbc/private/bodyimpl.h>

/* Copies of u0 and v0 (either may be NULL: that one stays as the scene gives it) in the body's
   layout (MBCBodyGetDisplacement's), for the dynamic start; after MBCSolverSetUp, before the first
   MBCSolverStep. */
PetscErrorCode MBCBodySetInitialState(MBCBody body, Vec u0, Vec v0)
{
  PetscFunctionBegin;
  if (!body) PetscFunctionReturn(0); /* a rank off the body */
  PetscValidHeaderSpecific(body, MBC_BODY_CLASSID, 1);
  PetscCheck(body->u, body->comm, PETSC_ERR_ARG_WRONGSTATE, "Body '%s': set its initial state after MBCSolverSetUp()", body->name);
  if (u0) {
    if (!body->u0) PetscCall(VecDuplicate(body->u, &body->u0));
    PetscCall(VecCopy(u0, body->u0));
    PetscCall(MBCBodyCheckFinite(body, body->u0, "initial displacement", 0.0));
  }
  if (v0) {
    if (!body->v0) PetscCall(VecDuplicate(body->u, &body->v0));
    PetscCall(VecCopy(v0, body->v0));
    PetscCall(MBCBodyCheckFinite(body, body->v0, "initial velocity", 0.0));
  }
  PetscFunctionReturn(0);
}

/* Whether the body starts from a given state (MBCBodySetInitialState or the scene's `initial`). */
PetscErrorCode MBCBodyHasInitialState(MBCBody body, PetscBool *has)
{
  PetscFunctionBegin;
  *has = (PetscBool)(body->u0 || body->v0 || body->desc.initial_u || body->desc.initial_v);
  PetscFunctionReturn(0);
}

/* x: the scene's per-node values (num_nodes x 3, scene order) at this rank's owned nodes. */
static PetscErrorCode BodyNodalValues(MBCBody body, const PetscReal values[], Vec x)
{
  PetscSection gsec;
  PetscScalar *a;
  PetscInt     pStart, pEnd, rstart;

  PetscFunctionBegin;
  PetscCall(DMGetGlobalSection(body->dm, &gsec));
  PetscCall(DMPlexGetChart(body->dm, &pStart, &pEnd));
  PetscCall(VecGetOwnershipRange(x, &rstart, NULL));
  PetscCall(VecGetArray(x, &a));
  for (PetscInt p = pStart; p < pEnd; p++) {
    const PetscInt n = MBCBodyPointNode(body, p);
    PetscInt       off;
    if (n < 0) continue;
    PetscCall(PetscSectionGetOffset(gsec, p, &off));
    if (off < 0) continue;
    for (PetscInt c = 0; c < 3; c++) a[off + c - rstart] = values[3 * n + c];
  }
  PetscCall(VecRestoreArray(x, &a));
  PetscFunctionReturn(0);
}

/* body->u and body->v from the initial state given (API, else scene); *hasu, *hasv: whether each
   was given (else they are left as they are). */
PetscErrorCode MBCBodyInitialState(MBCBody body, PetscBool *hasu, PetscBool *hasv)
{
  PetscFunctionBegin;
  *hasu = *hasv = PETSC_FALSE;
  if (body->u0) PetscCall(VecCopy(body->u0, body->u));
  else if (body->desc.initial_u) PetscCall(BodyNodalValues(body, body->desc.initial_u, body->u));
  if (body->v0) PetscCall(VecCopy(body->v0, body->v));
  else if (body->desc.initial_v) PetscCall(BodyNodalValues(body, body->desc.initial_v, body->v));
  *hasu = (PetscBool)(body->u0 || body->desc.initial_u);
  *hasv = (PetscBool)(body->v0 || body->desc.initial_v);
  if (*hasu) { /* prescribed DOFs as prescribed at t = 0, prescribed ones at rest */
    PetscCall(MBCBodyPrescribed(body, 0.0, body->g));
    PetscCall(MBCBodySetConstrainedRows(body, body->g, body->u));
  }
  if (*hasv) PetscCall(MBCBodySetConstrainedRows(body, NULL, body->v));
  if (body->desc.rigid && (*hasu || *hasv)) { /* a rigid body's state: the rigid motion that fits the nodes' best, its prescribed components as prescribed */
    PetscReal q[6];
    if (*hasu) {
      PetscCall(MBCBodyRigidMotion(body, body->u, q));
      PetscCall(VecZeroEntries(body->u));
      for (PetscInt j = 0; j < 6; j++) PetscCall(VecAXPY(body->u, q[j], body->Trig[j]));
      PetscCall(MBCBodyRigidPrescribed(body, 0.0, body->u, body->g)); /* the prescribed components' increment to t = 0 */
      PetscCall(VecAXPY(body->u, 1.0, body->g));
    }
    if (*hasv) {
      PetscCall(MBCBodyRigidMotion(body, body->v, q));
      PetscCall(VecZeroEntries(body->v));
      for (PetscInt j = 0; j < 6; j++) PetscCall(VecAXPY(body->v, q[j], body->Trig[j]));
      PetscCall(MBCBodyRigidPrescribed(body, 0.0, body->v, body->g)); /* prescribed components at rest */
      PetscCall(VecAXPY(body->v, 1.0, body->g));
      PetscCall(MBCBodyRigidPrescribed(body, 0.0, NULL, body->work));
      PetscCall(VecAXPY(body->v, -1.0, body->work));
    }
  }
  PetscFunctionReturn(0);
}
