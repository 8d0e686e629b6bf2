"""The matrix MUMPS factors on one rank: the Jacobian's structural nonzeros, not its node blocks.

The Jacobian is stored in node blocks (18 × 18 for 3363, SBAIJ: petsc/pattern.py), and PETSc
3.18 hands MUMPS every stored entry.  With contact multipliers many are zeros by construction:
the supported DOFs inside their nodes' blocks (unit rows, zero columns), the unused slots of the
multiplier nodes (held at zero; 12 of the 18 on the paper's tendon), the off-diagonal
multiplier–multiplier entries, which no law writes, and the couplings of every contact pair
seen so far (the pattern only grows) that no contact point uses at present.  MUMPS orders
and factors them as numbers, and a stored multiplier diagonal keeps it from its compressed
ordering for saddle points (ICNTL(12) = 2: each multiplier matched with a displacement it
constrains), which it applies only where a diagonal is structurally empty.  On the walking
stride's Jacobians (630 rows) PETSc passed 89 000 upper entries, 55 000 of them nonzero.

``CompactFactor`` is the preconditioner of the direct solve on one rank (a PETSc PCPYTHON
context, ``install``): its structure is J's nonzeros when its pattern last changed; each
set-up copies J's entries at that structure into a scalar SBAIJ matrix through a fixed index
map between the two value arrays (``MatSeqSBAIJGetArray``, 0.4 ms on the walking stride) and
factors that with MUMPS LDLᵀ, ICNTL(12) = 2 and ICNTL(6) = 5 unless the solve's -mat_mumps_*
options say otherwise (they reach this factor: it has the solve's prefix).  An unsymmetric
Jacobian (friction, pointwise fade forces: AIJ, MUMPS LU) is factored the same way, both
triangles of its nonzeros into a scalar AIJ matrix: on the μ = 0.3 stride's Jacobians (846 rows,
224 000 stored entries, 140 000 of them kept) a factorisation took 11.5 ms on every stored entry
and 4.1 ms compact with ICNTL(6) = 5 (5.6 ms with MUMPS's automatic scaling), with smaller
residuals; ordered by QAMD (``ORDERING_LU``) it takes half the flops.  A nonzero of J
outside the structure (a contact pair that comes into use, a law that writes there) adds its
position to the structure, and MUMPS analyses the grown one: the factor is J's whatever the law.
Measured (docs/parallel.md): the walking stride's factorisations 5.5 → 3.6 ms, whole runs 0.75–0.99
of the time with every stored entry, the same Newton iterations.  Negative and null pivots
(INFOG(12), INFOG(28)) are J's: dropped entries are zeros and the held DOFs keep their unit
diagonals, so the stability check reads the same counts (``inertia.pivot_counts`` reads this
factor through ``factor``).  A failed
factorisation fails the outer preconditioner (PCSetFailedReason), as MUMPS's own does.

The scaling of matching 5 is the analysis's, kept by every factorisation after it; values that
moved far since (fibres taking the load of a soft matrix) leave it stale and the factors wrong.
So every solve is checked: where ‖C y − x‖ > ``GUARD`` ‖x‖, or MUMPS gave up, on factors of an
earlier analysis, C is analysed again at its present values and the solve repeated (one MatMult
a solve; a factor read for its inertia before any solve is checked with x = 1 first).
"""
from __future__ import annotations

import ctypes

import numpy as np
from petsc4py import PETSc

from .diagnostics import petsc_library
from .database import insert, option, remove

#: MUMPS controls of the compact factor unless the solve's options say otherwise: ordering on the
#: compressed graph of matched pairs (ICNTL(12) = 2) after the matching that also gives a scaling
#: (ICNTL(6) = 5, MUMPS's default for it), which every later factorisation keeps until the next
#: analysis: 1.09x the sliding stride's frames/s against the bottleneck matching (3), after which
#: MUMPS scales every factorisation again (ICNTL(8) = 77, iterative, ~0.8 of its 2.5 ms).  Where
#: the values move by orders of magnitude after the analysis (a soft matrix whose fibres take the
#: load) the kept scaling ruins the factors: ``GUARD`` catches that and analyses again (module
#: docstring; docs/parallel.md, 2026-12-03).  Residuals of a random right-hand side 3e-8 (3:
#: 1e-8) on the stride's Jacobians, 4e-11 (3e-13) on bundle_hex7.  4 takes 170 ms an analysis on
#: the 8-element stride (3: ~30 ms); AMD without matching factors the strides as fast but
#: bundle_hex7 in 2.0e8 flops against 7.7e7
ORDERING = {12: 2, 6: 5}
#: ... of the compact LU (unsymmetric J: friction, pointwise fade forces): the same matching and
#: scaling, ordered by QAMD (ICNTL(7) = 6) instead of MUMPS's automatic choice (METIS here).
#: Measured on Coulomb μ = 0.3 stride Jacobians (2026-12-06, RINFOG(3)): 6.7e7 → 3.4e7 and
#: 7.8e7 → 3.8e7 flops at 4 elements (846 rows), 1.8e8 → 8.4–9.7e7 at 8, 7.8–8.3e7 → 4.1e7 on
#: the second subject, 3.7–7.7e8 → 3.0–7.5e8 on bundle_hex7 with μ = 0.3; the same Newton
#: iterations and answers, no analysis repeated (docs/parallel.md, 2026-12-06)
ORDERING_LU = {6: 5, 7: 6}
#: the largest relative residual ‖C y − x‖ / ‖x‖ of a solve with factors from an earlier analysis;
#: above it the structure is analysed again at the present values (a new scaling) and the solve
#: repeated.  Measured: 1e-15 – 9e-11 on the walking stride's solves with either matching; 0.3 –
#: 1.0 where the kept scaling had gone stale (the solver_default column at twist 0°)
GUARD = 1e-6
#: PETSc's PCFailedReason for a factorisation that failed otherwise than on a zero pivot
PC_FACTOR_OTHER = 4
_DOUBLE_P = ctypes.POINTER(ctypes.c_double)


class ValueArray:
    """The value array of a sequential SBAIJ or AIJ matrix (``size`` values) as a numpy view, for
    the ``with`` block only (``MatSeq{SB,}AIJGetArray``; the restore marks the matrix changed).
    ``read``: an AIJ matrix's values for reading (``MatSeqAIJGetArrayRead``: its state kept, so
    that a solver whose operator it is does not set up again; SBAIJ's restore keeps it anyway)."""

    def __init__(self, mat: PETSc.Mat, size: int, read: bool = False):
        self.mat, self.size, self.ptr = mat, size, _DOUBLE_P()
        kind = "SBAIJ" if mat.getType() == PETSc.Mat.Type.SEQSBAIJ else "AIJ"
        mode = "Read" if read and kind == "AIJ" else ""
        self.get, self.restore = f"MatSeq{kind}GetArray{mode}", f"MatSeq{kind}RestoreArray{mode}"

    def __enter__(self) -> np.ndarray:
        if getattr(petsc_library(), self.get)(ctypes.c_void_p(self.mat.handle), ctypes.byref(self.ptr)):
            raise RuntimeError(f"{self.get} failed")
        return np.ctypeslib.as_array(self.ptr, shape=(self.size,))

    def __exit__(self, *exc) -> None:
        getattr(petsc_library(), self.restore)(ctypes.c_void_p(self.mat.handle), ctypes.byref(self.ptr))


def stored_entries(J: PETSc.Mat) -> tuple[np.ndarray, np.ndarray]:
    """(row, column) of every stored value of a sequential SBAIJ J, in its value array's order:
    the blocks in block-CSR order, each bs × bs by columns; of a sequential AIJ J, its CSR
    order (not inode-compressed)."""
    if J.getType() == PETSc.Mat.Type.SEQAIJ:
        ia, ja = J.getRowIJ(symmetric=False, compressed=False)
        return np.repeat(np.arange(len(ia) - 1), np.diff(ia)), np.asarray(ja)
    ia, ja = J.getRowIJ(symmetric=False, compressed=True)
    D = J.getBlockSize()
    brow = np.repeat(np.arange(len(ia) - 1), np.diff(ia))
    r, c = np.tile(np.arange(D), D), np.repeat(np.arange(D), D)      # entry m of a block: r = m % D
    return (brow[:, None] * D + r).ravel(), (np.asarray(ja)[:, None] * D + c).ravel()


class CompactStructure:
    """Which stored values of J MUMPS gets (``src``, the compact matrix's CSR order) and which it
    does not (``dropped``; upper entries only of an SBAIJ J): off the diagonal, a held DOF's entries, the
    multiplier–multiplier ones and those zero in J now (couplings of contact pairs no point
    uses at present, contact curvature at rest), unless ``kept`` (positions row · n + column
    found nonzero since)."""

    def __init__(self, J: PETSc.Mat, held: np.ndarray, multiplier: np.ndarray, kept: np.ndarray):
        rows, cols = stored_entries(J)
        with ValueArray(J, len(rows), read=True) as a:
            values = a.copy()
        self.n, self.size = J.getSize()[0], len(rows)
        self.key = rows.astype(np.int64) * self.n + cols
        self.symmetric = J.getType() == PETSc.Mat.Type.SEQSBAIJ
        upper = cols >= rows if self.symmetric else np.ones(len(rows), dtype=bool)
        diag = rows == cols
        zero = ~diag & ((values == 0.0) | held[rows] | held[cols] | (multiplier[rows] & multiplier[cols]))
        zero &= ~np.isin(self.key, kept)
        take = np.flatnonzero(upper & ~zero)
        take = take[np.lexsort((cols[take], rows[take]))]
        self.src, self.dropped = take, np.flatnonzero(upper & zero)
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(rows[take], minlength=self.n))])
        self.indices = cols[take]

    def matrix(self) -> PETSc.Mat:
        """An empty scalar matrix with this structure: SBAIJ (upper) or AIJ, as J."""
        csr = (self.indptr.astype(PETSc.IntType), self.indices.astype(PETSc.IntType))
        C = (PETSc.Mat().createSBAIJ(self.n, 1, csr=csr, comm=PETSc.COMM_SELF) if self.symmetric
             else PETSc.Mat().createAIJ(self.n, csr=csr, comm=PETSc.COMM_SELF))
        C.setOption(PETSc.Mat.Option.NEW_NONZERO_ALLOCATION_ERR, True)
        return C

    def copy(self, J: PETSc.Mat, C: PETSc.Mat) -> np.ndarray:
        """Copy J's values into C; returns the positions (keys) of J's nonzero values that the
        structure dropped (then nothing is copied: the structure must grow)."""
        with ValueArray(J, self.size, read=True) as a:
            stray = self.dropped[a[self.dropped] != 0.0]
            if len(stray):
                return self.key[stray]
            with ValueArray(C, len(self.src)) as c:
                c[:] = a[self.src]
        C.assemble()                              # a new state: the inner PC factors again
        return stray


class CompactFactor:
    """PCPYTHON context: MUMPS LDLᵀ (SBAIJ J) or LU (AIJ J) of J's structural nonzeros (module
    docstring)."""

    def __init__(self, held: np.ndarray, multiplier: np.ndarray, prefix: str = "",
                 ordering: dict | None = None, symmetric: bool = True):
        self.held, self.multiplier, self.prefix = held, multiplier, prefix
        self.ordering = (ORDERING if symmetric else ORDERING_LU) if ordering is None else ordering
        self.kept = np.zeros(0, dtype=np.int64)
        self.structure: CompactStructure | None = None
        self.C: PETSc.Mat | None = None
        self._residual: PETSc.Vec | None = None
        self.ksp: PETSc.KSP | None = None
        self._source: tuple | None = None
        self.fresh = self.verified = False       # factors of this set-up's analysis; checked
        self.symmetric = symmetric               # LDLᵀ (SBAIJ J), else LU (AIJ J): no inertia
        self.analyses = 0                        # structures MUMPS analysed (growths included)
        self.reanalyses = 0                      # of them, for kept scalings gone stale (GUARD)
        self._analysed = False                   # the factor's analysis is done

    def setUp(self, pc: PETSc.PC) -> None:
        _, J = pc.getOperators()
        source = (J.handle, J.getInfo()["nz_allocated"])
        self.fresh = self.structure is None or source != self._source
        if self.fresh:
            self._build(J)
        self._source = source
        stray = self.structure.copy(J, self.C)
        if len(stray):                           # a coupling came into use: grow, factor J's
            self.kept = np.union1d(self.kept, stray)
            self._build(J)                       # from J's values now: nothing strays
            self.structure.copy(J, self.C)
            self.fresh = True
        self.verified = False
        self.ksp.setOperators(self.C, self.C)
        self._factor()

    def _build(self, J: PETSc.Mat) -> None:
        self.structure = CompactStructure(J, self.held, self.multiplier, self.kept)
        self.destroy()
        self.C = self.structure.matrix()
        self._residual = self.C.createVecLeft()
        self._analyse()

    def _analyse(self) -> None:
        """A new MUMPS factor of C: the next set-up analyses C's structure and values."""
        if self.ksp is not None:
            self.ksp.destroy()
        ksp = self.ksp = PETSc.KSP().create(comm=PETSc.COMM_SELF)
        ksp.setOptionsPrefix(self.prefix)        # -mat_mumps_* of the solve reach this factor
        ksp.setType(PETSc.KSP.Type.PREONLY)
        inner = ksp.getPC()
        inner.setType(PETSc.PC.Type.CHOLESKY if self.structure.symmetric else PETSc.PC.Type.LU)
        inner.setFactorSolverType("mumps")
        ksp.setOperators(self.C, self.C)
        inner.setFactorSetUpSolverType()
        for k, v in self.ordering.items():
            if option(f"mat_mumps_icntl_{k}", self.prefix) is None:
                inner.getFactorMatrix().setMumpsIcntl(k, v)
        self.analyses += 1
        self._analysed = False                   # the next set-up analyses (``_factor``)

    def _factor(self) -> None:
        """Factor C (``ksp.setUp``).  PETSc 3.18's MUMPS interface resets an ICNTL(7) set on the
        factor before its analysis; the analysis reads the database, so the ordering's value is
        put there for it (under the solve's prefix, unless the solve's options give one)."""
        order, key = self.ordering.get(7), f"{self.prefix}mat_mumps_icntl_7"
        put = order is not None and not self._analysed and option("mat_mumps_icntl_7", self.prefix) is None
        if put:
            insert(key, str(order))
        try:
            self.ksp.setUp()
        finally:
            if put:
                remove(key)
            self._analysed = True

    def apply(self, pc: PETSc.PC, x: PETSc.Vec, y: PETSc.Vec) -> None:
        if not self._solve_checked(x, y):
            petsc_library().PCSetFailedReason(ctypes.c_void_p(pc.handle), ctypes.c_int(PC_FACTOR_OTHER))

    def _solve_checked(self, x: PETSc.Vec, y: PETSc.Vec) -> bool:
        """y = C⁻¹ x; where the factors are an earlier analysis's and MUMPS gave up or the
        residual exceeds ``GUARD``, analyse again at the present values and solve again.
        False where MUMPS gave up on factors of a fresh analysis (its own factor error)."""
        self.ksp.solve(x, y)
        good = self.ksp.getConvergedReason() >= 0 and self._accurate(x, y)
        if not good and not self.fresh:
            self._analyse()                      # C's values now: a new scaling
            self._factor()
            self.fresh, self.reanalyses = True, self.reanalyses + 1
            self.ksp.solve(x, y)
        self.verified = True
        return self.ksp.getConvergedReason() >= 0

    def _accurate(self, x: PETSc.Vec, y: PETSc.Vec) -> bool:
        """‖C y − x‖ ≤ GUARD ‖x‖ (finite)."""
        r = self._residual
        self.C.mult(y, r)
        r.axpy(-1.0, x)
        rn, xn = r.norm(), x.norm()
        return bool(np.isfinite(rn) and rn <= GUARD * xn)

    def factor(self) -> PETSc.Mat | None:
        """The MUMPS factor (None before the first set-up), checked by a solve (``GUARD``) when no
        solve has used it yet: its pivots count the inertia (linalg/inertia.py)."""
        if self.ksp is None:
            return None
        if not self.verified:
            x, y = self.C.createVecs()
            x.set(1.0)
            self._solve_checked(x, y)
            x.destroy()
            y.destroy()
        try:
            return self.ksp.getPC().getFactorMatrix()
        except PETSc.Error:
            return None

    def view(self, pc: PETSc.PC, viewer: PETSc.Viewer) -> None:
        if self.ksp is not None:
            kind, part = ("LDLT", "upper entries") if self.structure.symmetric else ("LU", "entries")
            viewer.printfASCII(f"  MUMPS {kind} of the Jacobian's structural nonzeros "
                               f"({len(self.structure.src)} of {len(self.structure.src) + len(self.structure.dropped)} "
                               f"{part}):\n")
            self.ksp.view(viewer)

    def reset(self, pc: PETSc.PC) -> None:
        """PCReset (the Jacobian's pattern grew, petsc/problem.py): a new structure and analysis
        at the next set-up."""
        self.structure = None

    def destroy(self, pc: PETSc.PC | None = None) -> None:
        """Free the factor and the compact matrix (nothing after PETSc finalized: the outer
        PC of an object still alive at interpreter exit is destroyed then)."""
        if not PETSc.Sys.isFinalized():
            for obj in (self.ksp, self.C, self._residual):
                if obj is not None:
                    obj.destroy()
        self.ksp = self.C = self._residual = None


def compact_applies(problem, pc: PETSc.PC, wanted: bool) -> bool:
    """Whether the compact factorisation replaces ``pc`` (``solver.compact_factor``): one rank,
    MUMPS Cholesky of an SBAIJ Jacobian or LU of an AIJ one, with contact multipliers (their
    slots and blocks are the zeros it leaves out; without multipliers only the held DOFs'
    entries would go)."""
    kind = {PETSc.PC.Type.CHOLESKY: PETSc.Mat.Type.SEQSBAIJ, PETSc.PC.Type.LU: PETSc.Mat.Type.SEQAIJ}
    return (wanted and problem.comm.size == 1 and problem.n_constraints > 0
            and pc.getFactorSolverType() == "mumps" and kind.get(pc.getType()) == problem.J.getType())


def multiplier_mask(problem) -> np.ndarray:
    """Every DOF of the multiplier nodes (the blocks after the beams' nodes, PETSc numbering)."""
    D, lay = problem.model.dofs_per_node, problem.layout
    mask = np.zeros(D * lay.n_blocks, dtype=bool)
    blocks = lay.perm[problem.model.n_nodes:]
    mask[(D * blocks[:, None] + np.arange(D)).ravel()] = True
    return mask


def install_for(problem, ksp: PETSc.KSP, wanted: bool, prefix: str = "",
                ordering: dict | None = None) -> CompactFactor | None:
    """``install`` on ``ksp`` with ``problem``'s held DOFs and multiplier blocks where
    ``compact_applies`` (``wanted``: ``solver.compact_factor``); the context, or None."""
    if not compact_applies(problem, ksp.getPC(), wanted):
        return None
    return install(ksp, problem.fixed_mask, multiplier_mask(problem), prefix, ordering)


def install(ksp: PETSc.KSP, held: np.ndarray, multiplier: np.ndarray, prefix: str = "",
            ordering: dict | None = None) -> CompactFactor:
    """Make ``ksp``'s preconditioner the compact factorisation (one rank; SBAIJ J: Cholesky, AIJ
    J: LU); ``ordering``: its MUMPS controls (default ``ORDERING``, ``ORDERING_LU`` for LU)."""
    pc = ksp.getPC()
    context = CompactFactor(held, multiplier, prefix, ordering, symmetric=pc.getType() != PETSc.PC.Type.LU)
    pc.setType(PETSc.PC.Type.PYTHON)
    pc.setPythonContext(context)
    return context


def release_python_pc(ksp: PETSc.KSP, comm) -> None:
    """On one rank, a Python preconditioner (compact factor, fascicle Schur) lets go of its
    context before ``ksp`` is destroyed: a wrapper kept by an exception's traceback (the one PETSc
    passed a callback) left the PC to PETSc's final clean-up, which reset it after Python had
    finalised (a SEGV at exit)."""
    pc = ksp.getPC()
    if comm.size == 1 and pc.getType() == PETSc.PC.Type.PYTHON:
        pc.setType(PETSc.PC.Type.NONE)
