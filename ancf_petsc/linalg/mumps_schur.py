"""A sequential MUMPS LDLᵀ that stops at a Schur complement and solves in two halves, called
directly (ctypes on Debian's libdmumps, MUMPS 5.5.1): the part of MUMPS that PETSc 3.18's
interface keeps to itself.

For A = [[A_II, A_IΓ], [A_ΓI, A_ΓΓ]] (the Γ rows last) MUMPS eliminates I only and returns

    Σ_A = A_ΓΓ − A_ΓI A_II⁻¹ A_IΓ                         (ICNTL(19): ``SchurFactor.schur``)

and solves A x = b around a Schur system it does not own in two half solves (ICNTL(26)):

    condense: the forward pass, g = b_Γ − A_ΓI A_II⁻¹ b_I,   (the rest kept in MUMPS's RHS)
    expand:   the backward pass with x_Γ given, x_I = A_II⁻¹ (b_I − A_IΓ x_Γ).

So a caller can sum the condensed right-hand sides of several ranks, solve the summed Schur
system, and expand: one pass over the factor each way.  PETSc 3.18 offers the Schur complement
(MatFactorSetSchurIS) but solves the interior only whole (two passes each way, twice the memory
traffic of a factor that does not fit in cache).

The structure below mirrors ``DMUMPS_STRUC_C`` of /usr/include/dmumps_c.h (MUMPS 5.5.1, 32-bit
MUMPS_INT); ``SchurFactor`` checks the version MUMPS writes into it before using anything else.
"""
from __future__ import annotations

import ctypes
from ctypes import POINTER, c_char, c_double, c_int, c_int64

import numpy as np

#: the MUMPS release whose C structure this module mirrors
VERSION = "5.5.1"
LIBRARY = "libdmumps-5.5.so"
_int_p, _dbl_p = POINTER(c_int), POINTER(c_double)


class DMUMPS_STRUC_C(ctypes.Structure):
    """dmumps_c.h's DMUMPS_STRUC_C, field by field (natural alignment, as the C compiler lays
    it out)."""
    _fields_ = [
        ("sym", c_int), ("par", c_int), ("job", c_int), ("comm_fortran", c_int),
        ("icntl", c_int * 60), ("keep", c_int * 500), ("cntl", c_double * 15),
        ("dkeep", c_double * 230), ("keep8", c_int64 * 150),
        ("n", c_int), ("nblk", c_int), ("nz_alloc", c_int),
        ("nz", c_int), ("nnz", c_int64), ("irn", _int_p), ("jcn", _int_p), ("a", _dbl_p),
        ("nz_loc", c_int), ("nnz_loc", c_int64), ("irn_loc", _int_p), ("jcn_loc", _int_p),
        ("a_loc", _dbl_p),
        ("nelt", c_int), ("eltptr", _int_p), ("eltvar", _int_p), ("a_elt", _dbl_p),
        ("blkptr", _int_p), ("blkvar", _int_p), ("perm_in", _int_p),
        ("sym_perm", _int_p), ("uns_perm", _int_p),
        ("colsca", _dbl_p), ("rowsca", _dbl_p), ("colsca_from_mumps", c_int),
        ("rowsca_from_mumps", c_int),
        ("rhs", _dbl_p), ("redrhs", _dbl_p), ("rhs_sparse", _dbl_p), ("sol_loc", _dbl_p),
        ("rhs_loc", _dbl_p),
        ("irhs_sparse", _int_p), ("irhs_ptr", _int_p), ("isol_loc", _int_p), ("irhs_loc", _int_p),
        ("nrhs", c_int), ("lrhs", c_int), ("lredrhs", c_int), ("nz_rhs", c_int),
        ("lsol_loc", c_int), ("nloc_rhs", c_int), ("lrhs_loc", c_int),
        ("schur_mloc", c_int), ("schur_nloc", c_int), ("schur_lld", c_int),
        ("mblock", c_int), ("nblock", c_int), ("nprow", c_int), ("npcol", c_int),
        ("info", c_int * 80), ("infog", c_int * 80), ("rinfo", c_double * 40),
        ("rinfog", c_double * 40),
        ("deficiency", c_int), ("pivnul_list", _int_p), ("mapping", _int_p),
        ("size_schur", c_int), ("listvar_schur", _int_p), ("schur", _dbl_p),
        ("instance_number", c_int), ("wk_user", _dbl_p),
        ("version_number", c_char * 32), ("ooc_tmpdir", c_char * 256),
        ("ooc_prefix", c_char * 64), ("write_problem", c_char * 256), ("lwk_user", c_int),
        ("save_dir", c_char * 256), ("save_prefix", c_char * 256),
        ("metis_options", c_int * 40),
    ]


_LIB = None


def _library() -> ctypes.CDLL:
    global _LIB
    if _LIB is None:
        _LIB = ctypes.CDLL(LIBRARY)
        _LIB.dmumps_c.argtypes = [POINTER(DMUMPS_STRUC_C)]
        _LIB.dmumps_c.restype = None
    return _LIB


def mumps_controls(prefix: str, defaults: dict) -> tuple[dict, dict]:
    """(ICNTL, CNTL): ``defaults`` (ICNTL) overridden by -{prefix}mat_mumps_icntl_<k> and
    -{prefix}mat_mumps_cntl_<k> from the command line, for the MUMPS instances of the fascicle
    Schur solver (this module's, and PETSc's of a distributed interface system)."""
    from .database import option
    icntl, cntl = dict(defaults), {}
    for k in range(1, 61):
        value = option(f"mat_mumps_icntl_{k}", prefix)
        if value is not None:
            icntl[k] = int(value)
    for k in range(1, 16):
        value = option(f"mat_mumps_cntl_{k}", prefix)
        if value is not None:
            cntl[k] = float(value)
    return icntl, cntl


def _ptr(a: np.ndarray, kind):
    return a.ctypes.data_as(kind)


class MumpsError(RuntimeError):
    """MUMPS stopped with INFOG(1) < 0 in a phase other than the numeric factorisation."""


class SchurFactor:
    """LDLᵀ (MUMPS, SYM = 2, one process) of a symmetric n × n matrix given by its upper
    triangle in CSR (``indptr``, ``indices``, values set in ``values`` before each
    ``factor``), with the Schur complement on its last ``n_schur`` rows.  ``icntl``: MUMPS
    controls {k: value} (1-based k) set on top of MUMPS's defaults."""

    def __init__(self, indptr: np.ndarray, indices: np.ndarray, n_schur: int, icntl: dict,
                 cntl: dict | None = None):
        n = len(indptr) - 1
        self.n, self.n_schur = n, n_schur
        rows = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
        if np.any(np.asarray(indices) < rows):
            raise ValueError("SchurFactor takes the upper triangle only")
        self.irn = (rows + 1).astype(np.intc)
        self.jcn = (np.asarray(indices) + 1).astype(np.intc)
        self.values = np.zeros(len(self.irn))
        self.rhs = np.zeros(n)
        self.redrhs = np.zeros(max(n_schur, 1))
        self.schur_buffer = np.zeros(max(n_schur, 1) ** 2)
        self.listvar = np.arange(n - n_schur + 1, n + 1, dtype=np.intc)
        from mpi4py import MPI
        lib = _library()
        self.id = DMUMPS_STRUC_C()
        self.id.sym, self.id.par, self.id.job, self.id.comm_fortran = 2, 1, -1, MPI.COMM_SELF.py2f()
        lib.dmumps_c(ctypes.byref(self.id))
        version = self.id.version_number.decode(errors="replace").strip()
        if version != VERSION:
            raise MumpsError(f"libdmumps reports version {version!r}; this interface mirrors {VERSION}")
        self._alive = True
        self._check("initialisation")
        for k, v in {1: -1, 2: -1, 3: -1, 4: 0}.items():          # no output
            self.id.icntl[k - 1] = v
        for k, v in icntl.items():
            self.id.icntl[k - 1] = v
        for k, v in (cntl or {}).items():
            self.id.cntl[k - 1] = v
        self.id.n = n
        self.id.nz = len(self.irn)
        self.id.nnz = len(self.irn)
        self.id.irn, self.id.jcn = _ptr(self.irn, _int_p), _ptr(self.jcn, _int_p)
        self.id.a = _ptr(self.values, _dbl_p)
        if n_schur:
            self.id.size_schur = n_schur
            self.id.listvar_schur = _ptr(self.listvar, _int_p)
            self.id.icntl[19 - 1] = 1                    # centralised Schur complement
            self.id.schur = _ptr(self.schur_buffer, _dbl_p)
        self.id.rhs, self.id.nrhs, self.id.lrhs = _ptr(self.rhs, _dbl_p), 1, n
        self.id.redrhs, self.id.lredrhs = _ptr(self.redrhs, _dbl_p), max(n_schur, 1)
        self.analysed = False
        self.failed = False

    # ------------------------------------------------------------------ phases
    def _run(self, job: int) -> None:
        self.id.job = job
        _library().dmumps_c(ctypes.byref(self.id))

    def _check(self, phase: str) -> None:
        if self.id.infog[0] < 0:
            raise MumpsError(f"MUMPS {phase}: INFOG(1) = {self.id.infog[0]}, "
                             f"INFOG(2) = {self.id.infog[1]}")

    def factor(self) -> bool:
        """Analyse (the first time) and factor with the current ``values``; False when the
        numeric factorisation failed (INFOG(1) < 0, e.g. a singular interior block)."""
        if not self.analysed:
            self._run(1)
            self._check("analysis")
            self.analysed = True
        self._run(2)
        self.failed = self.id.infog[0] < 0
        return not self.failed

    @property
    def negative_pivots(self) -> int:
        """INFOG(12): negative pivots of the eliminated (interior) rows."""
        return int(self.id.infog[11])

    @property
    def null_pivots(self) -> int:
        """INFOG(28): null pivots found (with ICNTL(24) = 1; 0 otherwise)."""
        return int(self.id.infog[27])

    def schur(self) -> np.ndarray:
        """The Schur complement Σ_A (dense, symmetric; a copy)."""
        m = self.n_schur
        half = self.schur_buffer[:m * m].reshape(m, m)
        # MUMPS fills one triangle of a symmetric Schur complement: mirror it
        lower = np.tril(half, -1)
        tri = lower if np.any(lower) else np.triu(half, 1).T
        return tri + tri.T + np.diag(np.diag(half))

    def solve(self, b: np.ndarray) -> np.ndarray:
        """A⁻¹ b without a Schur complement (n_schur = 0)."""
        self.rhs[:] = b
        self.id.icntl[26 - 1] = 0
        self._run(3)
        self._check("solve")
        return self.rhs.copy()

    def condense(self, b_interior: np.ndarray, b_schur: np.ndarray | None = None) -> np.ndarray:
        """Forward pass: b_Γ − A_ΓI A_II⁻¹ b_I (b_Γ = 0 unless given); MUMPS keeps the rest for
        ``expand``."""
        ni = self.n - self.n_schur
        self.rhs[:ni] = b_interior
        self.rhs[ni:] = 0.0 if b_schur is None else b_schur
        self.id.icntl[26 - 1] = 1
        self._run(3)
        self._check("condensation")
        return self.redrhs[:self.n_schur].copy()

    def expand(self, x_schur: np.ndarray) -> np.ndarray:
        """Backward pass after ``condense``: x_I = A_II⁻¹ (b_I − A_IΓ x_Γ)."""
        self.redrhs[:self.n_schur] = x_schur
        self.id.icntl[26 - 1] = 2
        self._run(3)
        self._check("expansion")
        return self.rhs[:self.n - self.n_schur].copy()

    def destroy(self) -> None:
        """Free MUMPS's instance (before MPI is finalised; not left to garbage collection)."""
        if getattr(self, "_alive", False):
            self._run(-2)
            self._alive = False
