/* Private to the newton type: its data, shared by the step's direct (newton.c) and Krylov
   (newtonkrylov.c) solves. */
#pragma once

#include <mbc/private/multiplierimpl.h>

typedef struct {
  PetscReal     rho_scale;    /* rho = rho_scale / W_dd */
  PetscBool     rho_set;      /* -mbc_newton_rho given: else 1, or 1/2 where W_dd is estimated (NewtonRhoScale) */
  PetscInt      pgs_warm;     /* Gauss-Seidel sweeps before the first step */
  PetscInt      pgs_fallback; /* sweeps when the line search fails */
  PetscReal     sigma;        /* Armijo's constant */
  PetscInt      ls_max, nonmonotone;
  PetscInt      watchdog;     /* iterations without halving the best merit before going back to it */
  PetscBool     predictor;    /* from r = 0 with equilibrium constraints, the all-stick solution as the first iterate */
  PetscBool     closeall;     /* the predictor takes every contact closed, not only those the free increment closes */
  PetscBool     stepfailed;   /* the last Newton step's matrix could not be factored (dr = -phi) */
  PetscReal     shift;        /* relative diagonal shift of the Newton matrix */
  PetscReal     dense_fill;   /* a Newton matrix with at least this fraction of its entries nonzero is factored dense */
  PetscReal     w_dense_fill; /* W with at least this fraction of its entries nonzero: its products through a dense copy */
  PetscBool     slip_eliminate; /* each slipping contact's row along its slip direction eliminated (two rows, not three) */
  MBCMultiplier pgs;
  KSP           ksp;          /* the sparse LU (MUMPS; on several ranks under PCREDUNDANT) */
  KSP           kdense;       /* the dense LU (LAPACK; on several ranks ScaLAPACK's), prefix -mbc_newton_dense_ */
  MatType       densetype;    /* its matrix: MATDENSE, or MATSCALAPACK on several ranks */
  KSP           klu;          /* the one holding the kept factor */
  /* per W */
  Mat        Wprod;      /* W for the solve's products: its dense copy (-mbc_newton_w_dense_fill), or W (a reference) */
  VecScatter wtoall;     /* on several ranks with the copy: a vector gathered on every rank, into wxall */
  Vec        wxall;
  PetscReal *diag, *rho; /* 9, 2 per contact */
  PetscReal  rho_used;   /* the scale rho holds now (NewtonRhoScale but after a watchdog restart) */
  PetscBool *frozen;     /* per local row: a direction without flexibility */
  PetscReal *A, *B;      /* 9 per contact: the Jacobian blocks at the current iterate */
  PetscBool *active;     /* per contact: in the Newton system (not separated) */
  PetscReal *nu;         /* 2 per contact: its slip direction at the current iterate (0, 0: not slipping) */
  Vec        phi, dr, wdr, rt, ut, dalpha, alphat;
  PetscBool  wdr_of_dr;  /* wdr = W dr already (the kept inverse's residual computed it) */
  PetscReal *work;       /* 3 x (reduced size): one contact's rows of the Newton matrix */
  PetscInt  *mark, *cols;
  PetscInt   nbuilt;     /* the kept factor's active rows (-1: none kept) */
  IS         isbuilt;    /* and their indices: an all-stick system is the same while they are */
  PetscBool  keptslip;   /* the kept factor has slipping contacts: never reused */
  PetscInt   lsfail, pgssweeps, factors, kits; /* kits: Krylov iterations (matrix-free W) */
  KSP        kmf;        /* the Krylov solve of a step when W is a shell (prefix -mbc_newton_mf_) */
  /* the steps through a kept inverse (newtonlowrank.c) */
  PetscBool  lowrank;     /* -mbc_newton_lowrank */
  PetscReal  lowrank_max; /* rows differing from the reference beyond this fraction of the active ones: the direct solve */
  PetscInt   lowrank_dist_min; /* the correction M factored over the ranks from this size on */
  PetscBool *sticks;      /* per contact: active and sticking at the current iterate */
  PetscBool *refopen;     /* per contact: separated in Z's reference (identity rows), else sticking */
  Vec        refpending;  /* a restart's reference (W's layout), for the next Z if built for refW */
  Mat        refW;
  PetscBool  zbuilt;      /* Z tried for this W */
  Mat        Z;           /* the reference Newton matrix's inverse on its rows S that are not diagonal:
                             |S| x N dense, the rows S in W's layout, W's column layout; NULL: none */
  Vec        zx;          /* Z's rows S times a vector */
  PetscInt  *zrow;        /* per local row: its row of Z (in S), -1 in D (J_ref diagonal there) */
  PetscInt  *zsloc;       /* Z's local rows: their local rows of W */
  PetscScalar *zdinv;     /* per local row: Z's diagonal in D (1 / J_ref's), 0 in S */
  PetscScalar *WZ;        /* (W Z)_O: on the reference-separated rows O, nO x N on every rank (column-major) */
  PetscInt     nO, *oidx; /* |O|; per global row, its place in O (-1: not in O) */
  PetscInt    *wzcol;     /* per global row, its column of WZ (the order S, D of Z's blocks) */
  PetscReal  zsigma, zrho; /* its shift and the augmentations' scale it was built with */
  PetscInt   lowranks;    /* steps of the last solve taken through Z */
  PetscInt   zdirect, zdirectpending; /* direct steps since W or Z (Z is built once they cost as much); a restart's */
} MBC_Newton;

/* u = W r + q (+ G^T alpha) through nt->Wprod */
PETSC_INTERN PetscErrorCode MBCNewtonVelocity(MBCMultiplier, Vec, Vec);
/* y = W x, or y += W x (add), through nt->Wprod */
PETSC_INTERN PetscErrorCode MBCNewtonWMult(MBC_Newton *, Vec, PetscBool, Vec);

/* every rank's rows[0..nl) gathered on every rank, in rank order: *all (n of them, PetscFree) and
   the counts and displacements of the gather (PetscFree2(*cnt, *dsp)) */
PETSC_INTERN PetscErrorCode MBCNewtonRowsAllGather(MPI_Comm, PetscInt, const PetscInt[], PetscInt *, PetscInt **, PetscMPIInt **, PetscMPIInt **);

/* The Newton system on the active rows isA (nA on this rank, then the ng rigid modes on the last
   rank) solved by GMRES with a preconditioner from W^-1's approximation (W a shell). */
PETSC_INTERN PetscErrorCode MBCNewtonKrylovSolve(MBCMultiplier, IS, PetscInt, Vec, Vec, KSPConvergedReason *);

/* The Newton step dr = J^-1 (-phi) through the kept inverse of a reference state's Newton matrix,
   where it pays (W assembled, no equilibrium constraints, few rows differing from the reference)
   and meets its residual check: *done. Compose: the restart state (the reference). */
PETSC_INTERN PetscErrorCode MBCNewtonLowRankStep(MBCMultiplier, PetscBool *);
PETSC_INTERN PetscErrorCode MBCNewtonLowRankDestroyReference(MBC_Newton *);
PETSC_INTERN PetscErrorCode MBCNewtonLowRankCompose(MBCMultiplier);
