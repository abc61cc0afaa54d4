/* Package registration: the objects' class ids, and log events so -log_view shows where the time goes. */
#include <mbc/private/contactimpl.h>
#include <mbc/private/interfaceimpl.h>

PetscClassId  MBC_SCENE_CLASSID, MBC_SOLVER_CLASSID, MBC_BODY_CLASSID;
PetscLogEvent MBC_SceneLoad, MBC_BodyLoad, MBC_BodyAssemble, MBC_BodyFactor, MBC_BodySolve, MBC_Output;

static PetscBool MBCPackageInitialized = PETSC_FALSE;

PetscErrorCode MBCInitializePackage(void)
{
  PetscClassId classid;

  PetscFunctionBegin;
  if (MBCPackageInitialized) PetscFunctionReturn(0);
  MBCPackageInitialized = PETSC_TRUE;
  PetscCall(PetscClassIdRegister("MBCScene", &MBC_SCENE_CLASSID));
  PetscCall(PetscClassIdRegister("MBCSolver", &MBC_SOLVER_CLASSID));
  PetscCall(PetscClassIdRegister("MBCBody", &MBC_BODY_CLASSID));
  PetscCall(PetscClassIdRegister("mbcontact", &classid));
  PetscCall(PetscLogEventRegister("MBCSceneLoad", classid, &MBC_SceneLoad));
  PetscCall(PetscLogEventRegister("MBCBodyLoad", classid, &MBC_BodyLoad));
  PetscCall(PetscLogEventRegister("MBCBodyAssemble", classid, &MBC_BodyAssemble));
  PetscCall(PetscLogEventRegister("MBCBodyFactor", classid, &MBC_BodyFactor));
  PetscCall(PetscLogEventRegister("MBCBodySolve", classid, &MBC_BodySolve));
  PetscCall(PetscLogEventRegister("MBCOutput", classid, &MBC_Output));
  PetscCall(PetscLogEventRegister("MBCRankWait", classid, &MBC_RankWait));
  PetscCall(PetscLogEventRegister("MBCContactGather", classid, &MBC_ContactGather));
  PetscCall(PetscLogEventRegister("MBCGlobalSearch", classid, &MBC_GlobalSearch));
  PetscCall(PetscLogEventRegister("MBCLocalSearch", classid, &MBC_LocalSearch));
  PetscCall(PetscLogEventRegister("MBCContactIntegrate", classid, &MBC_ContactIntegrate));
  PetscCall(PetscLogEventRegister("MBCFlexibilityAssemble", classid, &MBC_FlexibilityAssemble));
  PetscCall(PetscLogEventRegister("MBCFlexibilityMult", classid, &MBC_FlexibilityMult));
  PetscCall(PetscLogEventRegister("MBCFlexibilityCoarse", classid, &MBC_FlexibilityCoarse));
  PetscCall(MBCMultiplierInitializePackage());
  PetscFunctionReturn(0);
}

/* Opens a result file for writing; an unwritable path is an error naming it. */
PetscErrorCode MBCFileOpenWrite(const char path[], FILE **fp)
{
  PetscFunctionBegin;
  *fp = fopen(path, "w");
  PetscCheck(*fp, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot write %s (does its folder exist?)", path);
  PetscFunctionReturn(0);
}
