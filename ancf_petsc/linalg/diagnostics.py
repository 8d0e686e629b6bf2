"""PETSc options after the run and PETSc errors: options PETSc never used (its own
``PetscOptionsUsed`` flags, reduced over the ranks), and PETSc errors turned into one line that
names the option and what works instead.  The input-side checks are in option_syntax.py."""
from __future__ import annotations

import re

import numpy as np
from mpi4py import MPI

from .database import copies, option_names, options_used, petsc_library  # noqa: F401 (imported from here)
from .option_syntax import PREFIX

#: options PETSc reads only in PetscFinalize, after the report is made
READ_AT_FINALIZE = ("options_left", "log_view", "log_summary", "malloc_dump", "memory_view",
                    "objects_dump", "log_all", "log_trace", "options_view", "check_pointer_intensity")
HINTS = {"mat_type": "the Jacobian's format is solver.matrix in the config (auto, aij, sbaij)",
         "help": ""}


def unused_command_line_options(comm) -> list[str]:
    """Options in PETSc's database (command line, PETSC_OPTIONS, .petscrc) that no PETSc object
    ever read, as ``-name``; collective (an option read on any rank counts as used).  An option
    a workflow's solve reads through its copy (``database.own_prefix``) is used; the copy is not
    listed."""
    made = copies()
    names = [n for n in option_names() if n not in READ_AT_FINALIZE and n not in made]
    copy_of = {original: copy for copy, original in made.items()}
    used = used_anywhere(names, comm)
    through_copy = used_anywhere([copy_of.get(n, n) for n in names], comm)
    return [f"-{n}" for n, u, c in zip(names, used, through_copy) if not (u or c)]


def used_anywhere(names: list[str], comm) -> list[bool]:
    """``options_used`` reduced over the ranks (collective; same list on every rank)."""
    mpi = comm.tompi4py()
    names = mpi.bcast(list(names), root=0)     # rank 0's list decides the order everywhere
    used = np.array(options_used(names), dtype=np.int32)
    if mpi.Get_size() > 1 and len(names):
        out = np.empty_like(used)
        mpi.Allreduce(used, out, op=MPI.MAX)
        used = out
    return [bool(u) for u in used]


def unused_line(option: str, source: str = "", prog: str = "ancf-solve", prefix: str = "") -> str:
    """One warning line of ``prog`` for an unused option (``source``: where it was set; ``prefix``:
    the run's ``solver.options_prefix``, under which it reads its solver options)."""
    base = option.lstrip("-")
    hint = HINTS.get(PREFIX.sub("", base)) or "misspelt, or not read by the solver in use"
    if prefix and not source and not base.lower().startswith(prefix.lower()) \
            and base.lower().startswith(("snes_", "ksp_", "pc_", "mat_")):
        # -snes_max_it 3 with options_prefix left_ was called 'misspelt'
        hint += f" (the config's solver.options_prefix is {prefix}: the solver reads -{prefix}{base})"
    where = f" ({source})" if source else ""
    return f"{prog}: warning: PETSc option {option}{where} was never used: {hint}"


# ------------------------------------------------------------------ PETSc errors → one line
def petsc_message(exc: Exception) -> str:
    """The last line of a PETSc error (the reason; the lines above are PETSc's call stack)."""
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    for ln in reversed(lines):
        text = re.sub(r"^\[\d+\]\s*", "", ln)
        if text and not text.startswith("See ") and not re.match(r"\w+\(\) at ", text):
            return text
    return lines[-1] if lines else "PETSc error"


#: factorisation packages without a Cholesky factorisation (PETSc 3.18)
LU_ONLY = ("superlu", "superlu_dist", "umfpack", "klu", "strumpack")


def solver_hint(pc: str, factor: str, ranks: int, has_package=lambda name: True) -> str:
    """What works instead of a preconditioner / factorisation PETSc refused."""
    direct = ("the default direct solver (-pc_type cholesky, MUMPS LDLᵀ) or -pc_type lu with "
              "-pc_factor_mat_solver_type mumps" + (" or superlu_dist" if ranks > 1 else ""))
    if pc in ("ilu", "icc") and ranks > 1:
        return (f"PETSc's {pc.upper()} is sequential: on {ranks} ranks use -pc_type bjacobi or asm "
                f"(-sub_pc_type {pc} on each rank's block), gamg, hypre, or {direct}")
    if pc in ("lu", "cholesky") and factor in ("petsc", "superlu", "umfpack", "klu", "cholmod") \
            and ranks > 1:
        return f"-pc_factor_mat_solver_type {factor} is sequential: on {ranks} ranks use {direct}"
    if pc == "hypre" and not has_package("hypre"):
        return f"this PETSc has no hypre: use -pc_type gamg, or {direct}"
    if pc == "cholesky" and factor in LU_ONLY:      # -pc_factor_mat_solver_type superlu alone
        return (f"-pc_factor_mat_solver_type {factor} factors LU only: add -pc_type lu, or use {direct}")
    if pc in ("lu", "cholesky", "ilu", "icc") and factor:
        return f"-pc_factor_mat_solver_type {factor} cannot do {pc} here: use {direct}"
    # not the one that failed (-ksp_type gmres -pc_type gamg was told to use it)
    others = [p for p in ("gamg", "hypre", "bjacobi", "asm") if p != pc and (p != "hypre" or has_package(p))]
    return f"use {direct}, or -ksp_type gmres with -pc_type {', '.join(others[:-1])} or {others[-1]}"


#: MUMPS errors (INFOG(1)) that a larger workspace margin (ICNTL(14), percent) cures
MUMPS_WORKSPACE_ERRORS = (-8, -9, -11, -14, -15, -17, -20)


def mumps_hint(infog1: int) -> str:
    """What to do about MUMPS's error INFOG(1) = ``infog1``."""
    if infog1 in MUMPS_WORKSPACE_ERRORS:
        return (f"MUMPS's workspace estimate was too small (INFOG(1) = {infog1}; delayed pivots): "
                "raise its margin, e.g. -mat_mumps_icntl_14 100 (percent)")
    if infog1 == -19:
        return ("-mat_mumps_icntl_23 caps MUMPS's working memory below what it needs "
                "(INFOG(1) = -19): raise the cap or drop the option")
    if infog1 == -13:
        return "MUMPS could not allocate its workspace (INFOG(1) = -13): use more ranks or nodes"
    return f"MUMPS failed with INFOG(1) = {infog1} (see the MUMPS user's guide)"
