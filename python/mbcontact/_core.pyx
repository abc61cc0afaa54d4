# cython: language_level=3
"""The petsc4py binding of mbcontact (docs/python.md): one Python class per C object, each
holding its handle; PETSc objects (Vec, DM, KSP) come back as petsc4py objects sharing the
solver's memory."""
from petsc4py import PETSc
from petsc4py.PETSc cimport Comm, Vec, DM, KSP, Mat, Viewer, PetscObject, PetscVec, PetscDM, PetscKSP, PetscMat, PetscViewer
cimport numpy as cnp
import numpy as np
from mbcontact.cmbcontact cimport *

cnp.import_array()

__all__ = ["Scene", "Solver", "Body", "Error", "VERSION"]

VERSION = MBC_VERSION_STRING.decode()
cdef int MBC_ERR_PYTHON = 83  # PETSC_ERR_USER: a Python exception in a callback


class Error(PETSc.Error):
    """A PETSc error raised by mbcontact's C code, with the message of the check that failed."""

    def __init__(self, int ierr, message):
        PETSc.Error.__init__(self, ierr)
        self.message = message

    def __str__(self):
        return f"{self.message} (PETSc error {self.ierr})"


cdef object _pending = None  # a callback's exception, raised again once its C call returns


cdef inline int CHKERR(PetscErrorCode ierr) except -1:
    global _pending
    cdef const char *text = NULL
    cdef char *specific = NULL
    if ierr == 0:
        return 0
    if _pending is not None:
        e, _pending = _pending, None
        raise e
    PetscErrorMessage(ierr, &text, &specific)
    msg = specific.decode(errors="replace").strip() if specific != NULL and specific[0] != 0 else ""
    if not msg and text != NULL:
        msg = text.decode(errors="replace")
    raise Error(ierr, msg)


cdef object _vec(PetscVec v):
    """The solver's own Vec as a petsc4py Vec (a new reference: same memory, same object)."""
    if v == NULL:
        return None
    cdef Vec ob = Vec()
    ob.vec = v
    CHKERR(PetscObjectReference(<PetscObject>v))
    return ob


cdef object _dm(PetscDM d):
    """The solver's own DM as a petsc4py DM (a new reference), or None."""
    if d == NULL:
        return None
    cdef DM ob = DM()
    ob.dm = d
    CHKERR(PetscObjectReference(<PetscObject>d))
    return ob


cdef object _comm(comm):
    return PETSc.COMM_WORLD if comm is None else comm


cdef class Scene:
    """A scene file written by mbcontact-prep (docs/scene.md): Scene().load("blocks.h5")."""
    cdef MBCScene scene

    def __cinit__(self):
        self.scene = NULL

    def __dealloc__(self):
        if not PetscFinalizeCalled:  # objects left at exit outlive PETSc: nothing to free then
            MBCSceneDestroy(&self.scene)

    def load(self, filename, comm=None):
        """Reads the scene on comm (default PETSC_COMM_WORLD); returns self."""
        cdef Comm c = _comm(comm)
        cdef MBCScene newscene = NULL
        cdef bytes f = str(filename).encode()
        CHKERR(MBCSceneLoad(c.comm, f, &newscene))
        MBCSceneDestroy(&self.scene)
        self.scene = newscene
        return self

    @classmethod
    def fromDict(cls, outdir, name, scene, meshes=None, comm=None):
        """A scene built from Python: scene is the YAML's content as a dict (docs/scene.md);
        meshes maps mesh names to in-memory meshio.Mesh objects (named regions as Gmsh
        physical groups or cell sets), which replace scene["meshes"] entries of that name.
        Rank 0 writes outdir/name_<mesh>.msh, name.yaml and, with mbcontact-prep in a
        subprocess (its h5py must not share a process with PETSc's HDF5), name.h5; every rank
        then loads it. A bad scene raises RuntimeError with mbcontact-prep's message."""
        import os
        import subprocess
        from mbcontact.meshgen import write_mesh
        from mbcontact.prep import prepare
        cdef Comm c = _comm(comm)
        h5, err = None, None
        if c.getRank() == 0:
            try:
                os.makedirs(str(outdir), exist_ok=True)
                scene = dict(scene)
                scene["meshes"] = dict(scene.get("meshes") or {})
                for key, mesh in (meshes or {}).items():
                    path = f"{name}_{key}.msh"
                    write_mesh(mesh, os.path.join(str(outdir), path))
                    scene["meshes"][key] = path
                h5 = prepare(str(outdir), name, scene)
            except (subprocess.CalledProcessError, ValueError, OSError) as e:
                err = f"mbcontact.Scene.fromDict({name!r}): {e} (mbcontact-prep's message is above)"
        if c.getSize() > 1:
            h5, err = c.tompi4py().bcast((h5, err), root=0)
        if err:
            raise RuntimeError(err)
        return cls().load(h5, c)

    def view(self, Viewer viewer=None):
        CHKERR(MBCSceneView(self._get(), viewer.vwr if viewer is not None else NULL))

    property filename:
        def __get__(self):
            cdef const char *f = NULL
            CHKERR(MBCSceneGetFilename(self._get(), &f))
            return f.decode()

    cdef MBCScene _get(self) except NULL:
        if self.scene == NULL:
            raise ValueError("mbcontact.Scene: no scene loaded (call load(filename) first)")
        return self.scene


cdef PetscErrorCode _monitor(MBCSolver s, PetscInt step, PetscReal time, void *ctx) except? -1 with gil:
    global _pending
    cdef Solver solver = <Solver>ctx
    try:
        solver._monitor(solver, step, time)
    except BaseException as e:
        _pending = e
        return MBC_ERR_PYTHON
    return 0


cdef class Body:
    """One body of a set-up solver, on the ranks of its sub-communicator (None elsewhere)."""
    cdef MBCBody body
    cdef object _solver  # keeps the solver (and so the body) alive

    def __cinit__(self):
        self.body = NULL

    property name:
        def __get__(self):
            cdef const char *n = NULL
            CHKERR(MBCBodyGetName(self.body, &n))
            return n.decode()

    def getDisplacement(self):
        """The solver's displacement Vec of this body (same memory: it changes as the solver steps)."""
        cdef PetscVec v = NULL
        CHKERR(MBCBodyGetDisplacement(self.body, &v))
        return _vec(v)

    def getVelocity(self):
        """The velocity Vec (dynamic analyses; None for a static one)."""
        cdef PetscVec v = NULL
        CHKERR(MBCBodyGetVelocity(self.body, &v))
        return _vec(v)

    def setInitialState(self, Vec displacement=None, Vec velocity=None):
        """The initial displacement and velocity of a dynamic analysis (copied; None: the scene's
        `initial`, else the static equilibrium and rest), in getDisplacement()'s layout. Call it
        after solver.setUp() and before solve() or the first step: the dynamic start takes them
        (prescribed DOFs as prescribed at t = 0) and finds the initial acceleration from them."""
        CHKERR(MBCBodySetInitialState(self.body, displacement.vec if displacement is not None else NULL,
                                      velocity.vec if velocity is not None else NULL))

    def getStress(self):
        """The cellwise stress (xx yy zz xy yz xz) of the current displacement, a new Vec on getStressDM()."""
        cdef PetscVec v = NULL
        CHKERR(MBCBodyCreateStress(self.body, &v))
        cdef Vec ob = Vec()
        ob.vec = v  # takes the new Vec's reference
        return ob

    def getDM(self):
        cdef PetscDM d = NULL
        CHKERR(MBCBodyGetDM(self.body, &d))
        return _dm(d)

    def getStressDM(self):
        cdef PetscDM d = NULL
        CHKERR(MBCBodyGetStressDM(self.body, &d))
        return _dm(d)

    def getKSP(self):
        """The KSP of the factored operator (after the first step; None before)."""
        cdef PetscKSP k = NULL
        CHKERR(MBCBodyGetKSP(self.body, &k))
        if k == NULL:
            return None
        cdef KSP ob = KSP()
        ob.ksp = k
        CHKERR(PetscObjectReference(<PetscObject>k))
        return ob

    def getOperators(self):
        """(K, M, Cb): the stiffness, the mass with the reservoir's added mass (None in a static
        analysis) and the absorbing boundaries' dashpots (None without), unconstrained, as
        petsc4py Mats sharing the solver's (after setUp)."""
        cdef PetscMat h[3]
        h[0] = h[1] = h[2] = NULL
        CHKERR(MBCBodyGetOperators(self.body, &h[0], &h[1], &h[2]))
        out = []
        for i in range(3):
            if h[i] == NULL:
                out.append(None)
                continue
            ob = Mat()
            (<Mat>ob).mat = h[i]
            CHKERR(PetscObjectReference(<PetscObject>h[i]))
            out.append(ob)
        return tuple(out)

    def getComm(self):
        return self.getDM().getComm()

    def view(self, Viewer viewer=None):
        CHKERR(MBCBodyView(self.body, viewer.vwr if viewer is not None else NULL))


cdef class Solver:
    """The bodies of a scene, time stepping and output: the C MBCSolver.

        solver = mbcontact.Solver().create()
        solver.setScene(mbcontact.Scene().load("blocks.h5"))
        solver.setFromOptions()        # -mbc_* options from PETSc.Options (with setOptionsPrefix)
        solver.solve()                 # or: while not solver.done: solver.step()
    """
    cdef MBCSolver solver
    cdef object _monitor

    def __cinit__(self):
        self.solver = NULL
        self._monitor = None

    def __dealloc__(self):
        if not PetscFinalizeCalled:
            MBCSolverDestroy(&self.solver)

    def create(self, comm=None):
        cdef Comm c = _comm(comm)
        cdef MBCSolver s = NULL
        CHKERR(MBCSolverCreate(c.comm, &s))
        MBCSolverDestroy(&self.solver)
        self.solver = s
        return self

    def destroy(self):
        CHKERR(MBCSolverDestroy(&self.solver))
        self._monitor = None
        return self

    cdef MBCSolver _get(self) except NULL:
        if self.solver == NULL:
            raise ValueError("mbcontact.Solver: not created (call create() first)")
        return self.solver

    def setScene(self, Scene scene):
        """The solver takes its own reference: the Scene object may go."""
        CHKERR(MBCSolverSetScene(self._get(), scene._get()))

    def setOptionsPrefix(self, prefix):
        cdef bytes p = (prefix or "").encode()
        CHKERR(MBCSolverSetOptionsPrefix(self._get(), p))

    def getOptionsPrefix(self):
        cdef const char *p = NULL
        CHKERR(MBCSolverGetOptionsPrefix(self._get(), &p))
        return p.decode() if p != NULL else None

    def setFromOptions(self):
        CHKERR(MBCSolverSetFromOptions(self._get()))

    def setUp(self):
        CHKERR(MBCSolverSetUp(self._get()))

    def step(self):
        """One time (or load) step; returns (step, time)."""
        CHKERR(MBCSolverStep(self._get()))
        return self.getStep()[0], self.time

    def solve(self):
        """Every step left."""
        CHKERR(MBCSolverSolve(self._get()))

    def getStep(self):
        """(steps done, steps of the run, time reached)."""
        cdef PetscInt step = 0, nsteps = 0
        cdef PetscReal t = 0
        CHKERR(MBCSolverGetStep(self._get(), &step, &nsteps, &t))
        return int(step), int(nsteps), float(t)

    property time:
        def __get__(self):
            return self.getStep()[2]

    property done:
        def __get__(self):
            step, nsteps, _ = self.getStep()
            return step >= nsteps

    def setMonitor(self, monitor):
        """monitor(solver, step, time) after each step (and after a dynamic analysis's initial
        state, step 0), on every rank; an exception in it stops the step and is raised again."""
        self._monitor = monitor
        if monitor is None:
            CHKERR(MBCSolverMonitorSet(self._get(), NULL, NULL, NULL))
        else:
            CHKERR(MBCSolverMonitorSet(self._get(), _monitor, <void *>self, NULL))

    def view(self, Viewer viewer=None):
        CHKERR(MBCSolverView(self._get(), viewer.vwr if viewer is not None else NULL))

    def getComm(self):
        """The solver's communicator (PetscObjectGetComm)."""
        cdef MPI_Comm cc
        CHKERR(PetscObjectGetComm(<PetscObject>self._get(), &cc))
        cdef Comm c = Comm()
        c.comm = cc
        return c

    def getNumBodies(self):
        cdef PetscInt n = 0
        CHKERR(MBCSolverGetNumBodies(self._get(), &n))
        return int(n)

    def getBody(self, b):
        """Body b (index or name) of a set-up solver; None on ranks outside the body."""
        cdef MBCBody cb = NULL
        cdef const char *n = NULL
        if isinstance(b, str):
            names = self.getBodyNames()
            if b not in names:
                raise KeyError(f"mbcontact.Solver.getBody: no body '{b}' (bodies: {', '.join(names)})")
            b = names.index(b)
        CHKERR(MBCSolverGetBody(self._get(), b, &cb))
        if cb == NULL:
            return None
        cdef Body body = Body()
        body.body = cb
        body._solver = self
        return body

    def getBodyNames(self):
        """Names of every body, on every rank (from the scene)."""
        cdef MBCScene sc = NULL
        cdef const char *name = NULL
        cdef PetscInt n = 0, b
        CHKERR(MBCSolverGetScene(self._get(), &sc))
        if sc == NULL:
            raise ValueError("mbcontact.Solver: no scene (call setScene() first)")
        CHKERR(MBCSceneGetNumBodies(sc, &n))
        names = []
        for b in range(n):
            CHKERR(MBCSceneGetBodyName(sc, b, &name))
            names.append(name.decode())
        return names

    def getMultipliers(self):
        """The contact multipliers of the last step: forces (normal, t1, t2) per point, a Vec
        in rank order sharing the solver's memory (None before contact; get it again after a step)."""
        cdef PetscVec v = NULL
        CHKERR(MBCSolverGetMultipliers(self._get(), &v))
        return _vec(v)

    def getContactPoints(self):
        """The contact points of the last step, couple order, on every rank, as a dict of numpy
        arrays (copies): position, normal, traction (n x 3), pressure (n), slip (n x 3; NaN on
        frictionless couples), state (n: 0 separated, 1 stick, 2 slip); with bonded couples
        (cohesion) also bonded (n: 1 while the bond holds) and break_time (n, NaN if it did not)."""
        cdef PetscInt n = 0
        cdef const PetscReal *x = NULL
        cdef const PetscReal *nrm = NULL
        cdef const PetscReal *p = NULL
        cdef const PetscReal *t = NULL
        cdef const PetscReal *sl = NULL
        cdef const PetscInt *st = NULL
        CHKERR(MBCSolverGetContactPoints(self._get(), &n, &x, &nrm, &p, &t, &sl, &st))
        out = {"position": np.zeros((n, 3)), "normal": np.zeros((n, 3)), "traction": np.zeros((n, 3)),
               "pressure": np.zeros(n), "slip": np.zeros((n, 3)), "state": np.zeros(n, dtype=np.int64)}
        cdef double[:, :] mx = out["position"], mn = out["normal"], mt = out["traction"], ms = out["slip"]
        cdef double[:] mp = out["pressure"]
        cdef long[:] mst = out["state"]
        cdef PetscInt i, d
        for i in range(n):
            mp[i] = p[i]
            mst[i] = st[i]
            for d in range(3):
                mx[i, d] = x[3 * i + d]
                mn[i, d] = nrm[3 * i + d]
                mt[i, d] = t[3 * i + d]
                ms[i, d] = sl[3 * i + d]
        cdef const PetscInt *jb = NULL
        cdef const PetscReal *jt = NULL
        CHKERR(MBCSolverGetContactJoints(self._get(), &n, &jb, &jt))
        if jb != NULL:
            out["bonded"] = np.array([jb[i] for i in range(n)], dtype=np.int64)
            out["break_time"] = np.array([jt[i] for i in range(n)])
        return out

