"""PETSc options of a solve: the defaults, the Jacobian's storage they imply, and putting them
into PETSc's options database around ``setFromOptions``.

Options come from three places, highest priority first: the command line (already in PETSc's
options database), the config's ``petsc:`` mapping, and ``DEFAULT_OPTIONS`` below.  The config
and default values are inserted only around ``setFromOptions`` and removed again.  With an
options prefix (``solver.options_prefix``, e.g. ``left_``) every option of the solve is read as
``-left_snes_type`` etc., so several solves in one process can be tuned apart.
"""
from __future__ import annotations

from petsc4py import PETSc

from ..errors import InputError
from .database import insert, option, option_values, remove
from .diagnostics import petsc_message, solver_hint
from .option_syntax import AT_FINISH_OPTIONS, check_value, parse_bool

def node_blocks_fit(model) -> bool:
    """Whether every node's DOFs are active (all beams interpolate their whole node block, e.g.
    3363), as SBAIJ node blocks need."""
    return all(len(b.vectors) == model.block.vectors_per_node for b in model.beams)


DEFAULT_OPTIONS = {
    "snes_type": "newtonls",
    "snes_linesearch_type": "basic",
    "snes_divergence_tolerance": "-1",
    "snes_rtol": "1e-10",
    "snes_stol": "1e-12",
    "snes_max_it": "15",
    "ksp_type": "preonly",
    # the Jacobian is a symmetric (energy) Hessian: MUMPS LDLᵀ (indefinite allowed) does half
    # the flops of LU (37-fascicle bundle: 11.1 s vs 18.5 s per run; scripts/bench_scaling.py);
    # -pc_factor_mat_solver_type mumps is added only where it applies (``factor_package``)
    "pc_type": "cholesky",
    # null-pivot detection: a mechanism the load does not excite (the unloaded Achilles bundle,
    # pinned at one node per subtendon and sliding without friction, can tilt as a whole; a
    # beam held only in position can rotate) is left out of the Newton step instead of being
    # amplified by a pivot at rounding level; |pivot| <= 1e-11 ||A|| after MUMPS's scaling
    # (1e-12 ... 1e-10 all solve the psi = 0 column in the same 73 iterations, 1e-8 treats
    # real pivots as null).  Read by MUMPS only.
    "mat_mumps_icntl_24": "1",
    "mat_mumps_cntl_3": "1e-11",
}
#: preconditioners whose factorisation package defaults to MUMPS
MUMPS_PCS = ("lu", "cholesky")
#: ``solver.linear: fieldsplit`` (linalg/fieldsplit.py): flexible GMRES (right-preconditioned: it
#: tests the true residual; it keeps the preconditioned vectors, whose large multiplier
#: components make GMRES's recombination lose digits: 37 fascicles, true residual 2e-6 instead
#: of 7e-10) around the exact inverse of the Jacobian without the contact curvature between
#: fascicles; these replace the factorisation entries of DEFAULT_OPTIONS
FIELDSPLIT_OPTIONS = {
    "ksp_type": "fgmres",
    "ksp_pc_side": "right",
    "ksp_rtol": "1e-9",
    "ksp_gmres_restart": "100",
    "ksp_max_it": "100",
}


class SolverOptionError(InputError):
    """PETSc refused the solver the options ask for (exit 2, one line naming the options)."""


#: preconditioners PETSc runs on an SBAIJ matrix (MUMPS LDLᵀ, incomplete Cholesky, and the
#: block/overlapping ones around them); LU, ILU, GAMG and hypre need AIJ
SBAIJ_PCS = ("cholesky", "icc", "bjacobi", "asm", "jacobi", "none")


#: factorisations that assume a symmetric matrix (refused when the Jacobian is not)
SYMMETRIC_PCS = ("cholesky", "icc")


def matrix_type(model, choice: str, config_options: dict, prefix: str = "",
                linear: str = "direct", symmetric: bool = True) -> str:
    """The Jacobian's storage, 'aij' or 'sbaij' (``solver.matrix``; the options in effect are the
    command line's, then the config's ``petsc:``, then ``DEFAULT_OPTIONS``).

    ``auto`` takes SBAIJ node blocks when they pay and work: MUMPS LDLᵀ (the default solver) or
    the fascicle Schur solver (``linear`` 'fieldsplit') on 3363 beams (3333 beams hold half of
    each node block at zero).  An unsymmetric Jacobian (``symmetric`` False: Coulomb friction
    at an interface) takes AIJ and refuses a symmetric factorisation."""
    pc, factor = factor_package(config_options, prefix, symmetric)
    if not symmetric and pc in SYMMETRIC_PCS:
        # named where it was given: the command line wins over the config's petsc: section
        key = f"-{prefix}pc_type" if option("pc_type", prefix) is not None else "petsc.pc_type"
        raise InputError(key, f"{pc} factors a symmetric matrix, but the Jacobian is "
                              "unsymmetric (friction of contact.tangential); use lu")
    if linear == "fieldsplit":
        pc, factor = "cholesky", "mumps"        # symmetric sub-blocks and MUMPS on the multipliers
    full = node_blocks_fit(model)
    # the VI Newton types reduce the Jacobian to its free rows (MatCreateSubMatrix), which
    # segfaults on SBAIJ (-snes_type vinewtonssls, measured): they get AIJ
    vi = option_in_effect("snes_type", config_options, prefix, symmetric).startswith("vi")
    # so does -snes_fd_color: its colouring needs AIJ ('PETSC_ERROR in the linear solver ...:
    # Ordering requires IJ' at the first level on SBAIJ)
    if option("snes_fd_color", prefix) is not None or "snes_fd_color" in config_options:
        vi = vi or bool(parse_bool(option_in_effect("snes_fd_color", config_options, prefix) or "true"))
    if choice == "auto":
        return "sbaij" if (pc == "cholesky" and factor == "mumps" and full and symmetric and not vi) else "aij"
    if choice == "sbaij":
        if not full:
            raise InputError("solver.matrix", "sbaij needs elements that use their whole node block "
                                               "on every beam (3333 holds half of 3363's); use aij or auto")
        if pc not in SBAIJ_PCS or not symmetric:
            raise InputError("solver.matrix", f"PETSc's pc_type {pc} does not run on sbaij"
                              + ("" if symmetric else " (an unsymmetric Jacobian: contact.tangential "
                                 "friction)") + "; use aij or auto")
    return choice


def default_options(symmetric: bool = True) -> dict:
    """``DEFAULT_OPTIONS``, with LU instead of LDLᵀ for an unsymmetric Jacobian."""
    return DEFAULT_OPTIONS if symmetric else DEFAULT_OPTIONS | {"pc_type": "lu"}


def option_in_effect(key: str, config_options: dict, prefix: str = "", symmetric: bool = True) -> str:
    """The value of a PETSc option: command line, else config ``petsc:``, else the defaults."""
    value = option(key, prefix)
    if value is not None:
        return value
    return str(config_options.get(key, default_options(symmetric).get(key, "")))


def factor_package(config_options: dict, prefix: str = "", symmetric: bool = True) -> tuple[str, str]:
    """(pc_type, factorisation package) in effect.  The package defaults to MUMPS for LU and
    Cholesky only: ILU, ICC and the block preconditioners keep PETSc's own default."""
    pc = option_in_effect("pc_type", config_options, prefix, symmetric)
    factor = option_in_effect("pc_factor_mat_solver_type", config_options, prefix, symmetric)
    if not factor and pc in MUMPS_PCS:
        factor = "mumps"
    return pc, factor


#: SNES types that take no line search, so no line-search pre-check either (sections neither
#: turned nor steps held: -snes_type newtontr ran configs/bending_neohookean.yaml in 203 Newton
#: iterations with solver.section_update rotation and linear alike, its header saying "line
#: search basic; Newton steps turn the sections")
NO_LINE_SEARCH = ("newtontr", "ksponly", "ksptransposeonly")
#: options read only when the factorisation is first set up, after ``setFromOptions``
DEFERRED_OPTIONS = ("mat_mumps_", "mat_superlu")


def configure_options(snes: PETSc.SNES, config_options: dict, defaults: dict,
                      prefix: str = "", symmetric: bool = True) -> tuple[str, list[str]]:
    """setFromOptions with command line > config ``petsc:`` > defaults; leaves the DB as found
    except for the config's options and the default factorisation options (``DEFERRED_OPTIONS``,
    read by MUMPS at its first symbolic factorisation): those stay for the run, like command-line
    ones (-ksp_view, -ksp_converged_reason are read at every solve), until ``LoadStepper.close``.

    The SNES must carry ``prefix`` already (``snes.setOptionsPrefix``).  Returns the line-search
    type in effect (petsc4py 3.18 cannot query it from the SNES) and the option names (with the
    prefix) left in the database.  A value or combination PETSc refuses raises
    ``SolverOptionError`` (the same on every rank: the options are).  A type without a line
    search (``NO_LINE_SEARCH``) has line search 'none'.
    """
    bad = prefixed_option_problem(prefix)
    if bad:
        raise SolverOptionError("", bad)
    inserted = []
    for source in (config_options, defaults):
        for key, value in source.items():
            if option(key, prefix) is None and key not in AT_FINISH_OPTIONS:
                insert(prefix + key, value)
                inserted.append(prefix + key)
    n = len(prefix)
    kept = [k for k in inserted if k[n:] in config_options or k[n:].startswith(DEFERRED_OPTIONS)]
    try:
        snes.setFromOptions()
        linesearch = ("none" if snes.getType() in NO_LINE_SEARCH
                      else option("snes_linesearch_type", prefix) or "bt")      # PETSc's own default
    except PETSc.Error as exc:
        for key in kept:
            remove(key)
        raise SolverOptionError("", refused(exc, config_options, snes.getComm().getSize(), prefix,
                                            symmetric)) from None
    finally:
        for key in inserted:
            if key not in kept:
                remove(key)
    return linesearch, kept


def prefixed_option_problem(prefix: str) -> str | None:
    """The first option under ``prefix`` (``solver.options_prefix``) that PETSc would refuse, as
    one line, or None.  Options without a prefix are checked before PETSc starts
    (config/options_files.py); the prefix of a solve is known only from its config."""
    if not prefix:
        return None
    # read without marking them used: -left_snes_maxit (options_prefix left_) was never reported
    for name, value in sorted(option_values().items()):
        if name.lower().startswith(prefix.lower()):           # PETSc's names ignore case
            value = value or None                  # a flag without a value: None
            why = check_value(name[len(prefix):], value)
            if why:
                return f"PETSc option -{name}" + (f" {value}" if value else "") + f": {why}"
    return None


def solver_options(config_options: dict, prefix: str = "", symmetric: bool = True) -> str:
    """``-ksp_type gmres -pc_type ilu`` as in effect (for messages)."""
    pc, factor = factor_package(config_options, prefix, symmetric)
    text = f"-{prefix}ksp_type {option_in_effect('ksp_type', config_options, prefix)} -{prefix}pc_type {pc}"
    return text + (f" -{prefix}pc_factor_mat_solver_type {factor}" if factor else "")


def refused(exc: Exception, config_options: dict, ranks: int, prefix: str = "",
            symmetric: bool = True) -> str:
    """One line: PETSc's reason, the options in effect and what works instead.  With MUMPS LU or
    LDLᵀ (the defaults, which factor every matrix here) the solver is not to blame: another
    option PETSc read with it is."""
    pc, factor = factor_package(config_options, prefix, symmetric)
    if factor == "mumps" and pc in MUMPS_PCS and PETSc.Sys.hasExternalPackage("mumps"):
        return (f"PETSc refused an option while setting up the solver on {ranks} rank(s): "
                f"{petsc_message(exc)}; check the PETSc options"
                + (f" with the prefix -{prefix}" if prefix else "") + " given on the command line, "
                "in PETSC_OPTIONS or options files, and under petsc: in the config")
    return (f"PETSc refused the solver options {solver_options(config_options, prefix, symmetric)} on {ranks} "
            f"rank(s): {petsc_message(exc)}; {solver_hint(pc, factor, ranks, PETSc.Sys.hasExternalPackage)}")


def run_defaults(config_options: dict, ranks: int, atol: float, prefix: str = "",
                 linear: str = "direct", saddle_point: bool = False, symmetric: bool = True,
                 law_defaults: dict | None = None) -> dict:
    """``DEFAULT_OPTIONS`` completed for this solve: MUMPS where it is the factorisation package,
    its sequential root on a few ranks, room for delayed pivots when the Jacobian is a
    saddle-point matrix (contact multipliers), and the absolute tolerance ``atol``; for the
    fascicle Schur solver (``linear`` 'fieldsplit') ``FIELDSPLIT_OPTIONS`` instead of the
    factorisation; LU for an unsymmetric Jacobian (``symmetric`` False); the options the
    model's laws ask for (``law_defaults``, e.g. a line search for friction) over the rest."""
    defaults = dict(default_options(symmetric)) | (law_defaults or {})
    _, factor = factor_package(config_options, prefix, symmetric)
    if linear == "fieldsplit":
        defaults = {k: v for k, v in defaults.items()
                    if k not in ("ksp_type", "pc_type") and not k.startswith("mat_mumps_")}
        defaults.update(FIELDSPLIT_OPTIONS)
        # a Krylov residual cannot fall below the rounding of J x: stop it well below the
        # Newton tolerance instead of relative to a right-hand side that is already tiny
        defaults["ksp_atol"] = f"{1e-2 * atol:.3e}"
        factor = ""
    if factor == "mumps" and option("pc_factor_mat_solver_type", prefix) is None \
            and "pc_factor_mat_solver_type" not in config_options:
        defaults["pc_factor_mat_solver_type"] = "mumps"
    if factor == "mumps" and 1 < ranks <= 4:
        # on a few ranks MUMPS's ScaLAPACK root front (a 1×2 process grid: LU, twice the
        # flops of the LDLᵀ root) is slower than factoring the root on one rank (37-fascicle
        # bundle, 22k DOFs, 2 ranks: 0.72 -> 0.65 s per factorisation), and only a sequential
        # root gives the stability check its negative-pivot count (inertia.py); on more ranks
        # PETSc sets it to 1 itself while null-pivot detection (ICNTL(24), DEFAULT_OPTIONS) is on, so
        # the root is parallel only with -mat_mumps_icntl_24 0 as well
        defaults["mat_mumps_icntl_13"] = "1"
    if factor == "mumps" and saddle_point:
        # the zero multiplier block delays pivots beyond MUMPS's 20 % workspace margin: the
        # 37-fascicle bundle on 2 ranks stopped with INFOG(1) = -9 (FACTOR_OUTMEMORY) at 20 %
        # and runs from 35 % on
        defaults["mat_mumps_icntl_14"] = "50"
    defaults["snes_atol"] = f"{atol:.3e}"
    return defaults
