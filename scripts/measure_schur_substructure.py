#!/usr/bin/env python3
"""Would a substructured multiplier Schur complement reach issue 16's 1.8×?  A measurement, not
a solver: the fascicle Schur preconditioner's S (petsc/fieldsplit.py) of a bundle at its
reference state, split by the 2-rank beam partition into each rank's interior multipliers and
the multipliers on the cut; then, with sequential MUMPS LDLᵀ, the numeric factorisation of

* the whole S (what one rank does now),
* each rank's block with MUMPS forming the Schur complement on the cut itself (ICNTL(19) through
  PETSc's MatFactorSetSchurIS, called with ctypes: petsc4py 3.18 does not wrap it),
* the summed interface system (dense LDLᵀ),

and checks the substructuring: the blocks' Schur complements add up to the interface system of
S (against dense elimination), and the negative pivots add up to S's (the stability count).

Usage: python scripts/measure_schur_substructure.py [--config configs/bundle_hex37.yaml] [--repeat 3]
"""
from __future__ import annotations

import argparse
import ctypes
import os
import sys
import time

from mpi4py import MPI  # noqa: F401  (MPI before PETSc)
import petsc4py
petsc4py.init([])
from petsc4py import PETSc  # noqa: E402

import numpy as np  # noqa: E402
import scipy.linalg as sl  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)
from ancf_petsc.config.parse import load_config  # noqa: E402
from ancf_petsc.contact import build_contact  # noqa: E402
from ancf_petsc.model.build import build_model  # noqa: E402
from ancf_petsc.parallel.partition import beam_owner, make_layout  # noqa: E402
from ancf_petsc.petsc.fascicles import fascicle_split  # noqa: E402
from ancf_petsc.petsc.fieldsplit import FascicleSchur  # noqa: E402
from ancf_petsc.petsc.problem import Problem  # noqa: E402

LIB = ctypes.CDLL("libpetsc_real.so.3.18")


def schur_of(config: str):
    """S at the reference state and the (M, 2) ranks of every multiplier's two beams (2-rank
    beam partition)."""
    spec = load_config(config)
    model = build_model(spec)
    contact = build_contact(model, spec.contact, lambda *_: None)
    comm = PETSc.COMM_SELF
    layout = make_layout(model, "blocks", 1, 0, contact, comm.tompi4py())
    problem = Problem(model, layout, comm, contact, "sbaij")
    X = problem.q0.copy()
    problem.jacobian(None, X, problem.J, problem.J)
    split = fascicle_split(problem)
    pc = PETSc.PC().create(comm=comm)
    pc.setOperators(problem.J, problem.J)
    schur = FascicleSchur(split, comm)
    schur.setUp(pc)
    owner = beam_owner(model, 2, contact)
    beam_rank = np.array([owner[b.element_offset] for b in model.beams])
    return schur.S, beam_rank[split.z_beams]


def factor(A: PETSc.Mat, schur_rows: np.ndarray | None, repeat: int):
    """Sequential MUMPS LDLᵀ of A (the fascicle solver's settings), the Schur complement on
    ``schur_rows`` formed by MUMPS if given; (factor, best numeric time)."""
    ksp = PETSc.KSP().create(comm=PETSc.COMM_SELF)
    ksp.setOperators(A, A)
    ksp.setType("preonly")
    pc = ksp.getPC()
    pc.setType("cholesky")
    pc.setFactorSolverType("mumps")
    pc.setFactorSetUpSolverType()
    F = pc.getFactorMatrix()
    for k, v in ((24, 0), (14, 100), (7, 0)):
        F.setMumpsIcntl(k, v)
    if schur_rows is not None:
        iset = PETSc.IS().createGeneral(schur_rows.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
        if LIB.MatFactorSetSchurIS(ctypes.c_void_p(F.handle), ctypes.c_void_p(iset.handle)):
            sys.exit("MatFactorSetSchurIS failed")
    ksp.setUp()                                   # analysis and a first factorisation
    best = np.inf
    for _ in range(repeat):
        A.shift(1e-300)                           # a new matrix state: PCSetUp refactors
        A.shift(-1e-300)
        ksp.setOperators(A, A)
        t0 = time.perf_counter()
        ksp.setUp()
        best = min(best, time.perf_counter() - t0)
    return ksp, F, best


def schur_complement(F: PETSc.Mat) -> np.ndarray:
    """The dense Schur complement MUMPS formed (MatFactorCreateSchurComplement)."""
    S, status = ctypes.c_void_p(), ctypes.c_int()
    if LIB.MatFactorCreateSchurComplement(ctypes.c_void_p(F.handle), ctypes.byref(S), ctypes.byref(status)):
        sys.exit("MatFactorCreateSchurComplement failed")
    m, n = ctypes.c_int(), ctypes.c_int()             # PetscInt is 32-bit in Debian's PETSc
    LIB.MatGetSize(S, ctypes.byref(m), ctypes.byref(n))
    data = ctypes.POINTER(ctypes.c_double)()
    LIB.MatDenseGetArray(S, ctypes.byref(data))
    out = np.ctypeslib.as_array(data, shape=(n.value, m.value)).T.copy()   # column-major
    LIB.MatDenseRestoreArray(S, ctypes.byref(data))
    LIB.MatDestroy(ctypes.byref(S))
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default=os.path.join(ROOT, "configs", "bundle_hex37.yaml"))
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    if PETSc.IntType().itemsize != 4:
        sys.exit("this measurement reads PETSc sizes as 32-bit integers")
    S, ranks = schur_of(args.config)
    M = S.getSize()[0]
    cut = np.flatnonzero(ranks[:, 0] != ranks[:, 1])
    inner = [np.flatnonzero((ranks[:, 0] == r) & (ranks[:, 1] == r)) for r in (0, 1)]
    print(f"S: {M} multipliers; interior {len(inner[0])} + {len(inner[1])}, on the cut {len(cut)}")
    _, F, t_full = factor(S, None, args.repeat)
    print(f"whole S, one rank:         {t_full:.3f} s  ({F.getMumpsRinfog(3):.2g} flops, "
          f"{F.getMumpsInfog(12)} negative pivots)")
    sigma = -S.createSubMatrix(*(PETSc.IS().createGeneral(cut.astype(PETSc.IntType),
                                                          comm=PETSc.COMM_SELF),) * 2
                               ).convert("dense").getDenseArray().copy()     # − S_ΓΓ, added twice below
    times, negative = [], 0
    for r in (0, 1):
        rows = np.concatenate([inner[r], cut])
        iset = PETSc.IS().createGeneral(rows.astype(PETSc.IntType), comm=PETSc.COMM_SELF)
        A = S.createSubMatrix(iset, iset)
        A.setOption(PETSc.Mat.Option.SYMMETRIC, True)
        _, Fr, t = factor(A, np.arange(len(inner[r]), len(rows)), args.repeat)
        sigma += schur_complement(Fr)
        negative += Fr.getMumpsInfog(12)
        times.append(t)
        print(f"rank {r}'s block + Schur:   {t:.3f} s  ({len(inner[r])} + {len(cut)} multipliers, "
              f"{Fr.getMumpsRinfog(3):.2g} flops)")
    t0 = time.perf_counter()
    _, d, _ = sl.ldl(sigma)
    t_sigma = time.perf_counter() - t0
    negative += int(np.sum(np.linalg.eigvalsh(0.5 * (d + d.T)) < 0))
    print(f"interface system, dense:   {t_sigma:.3f} s  ({len(cut)} × {len(cut)})")
    Sd = S.convert("dense").getDenseArray()
    rest = np.setdiff1d(np.arange(M), cut)
    ref = Sd[np.ix_(cut, cut)] - Sd[np.ix_(cut, rest)] @ np.linalg.solve(Sd[np.ix_(rest, rest)], Sd[np.ix_(rest, cut)])
    print(f"check: interface system vs dense elimination {np.abs(sigma - ref).max() / np.abs(ref).max():.1e}; "
          f"negative pivots {negative} (whole S: {F.getMumpsInfog(12)})")
    two_ranks = max(times) + t_sigma
    print(f"per factorisation of S: one rank {t_full:.3f} s, substructured on two ranks "
          f"{two_ranks:.3f} s (the slower block + the interface system; its allreduce not included)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
