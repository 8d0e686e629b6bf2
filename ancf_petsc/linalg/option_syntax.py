"""PETSc options as input: config values and command-line options checked the way PETSc parses them.

``check_value`` is pure Python (the config layer calls it before PETSc is initialised); it
mirrors PETSc 3.18's ``PetscOptionsStringToReal/Int/Bool`` (strtod/strtol over the whole string,
plus the words DEFAULT and DECIDE) and its type registries (case-sensitive names, e.g. ``lu``;
case-insensitive enum values, e.g. ``nonzero``).  tests/apps/test_edges.py checks these tables against
the PETSc library itself.  Options not in the tables are passed on unchecked; a misspelt one is
caught after the run by ``diagnostics.unused_command_line_options`` (PETSc's own
``PetscOptionsUsed`` flags).
"""
from __future__ import annotations

import re

SNES_TYPES = ("anderson", "aspin", "composite", "fas", "ksponly", "ksptransposeonly", "ms", "nasm",
              "ncg", "newtonls", "newtontr", "ngmres", "ngs", "nrichardson", "patch", "python", "qn",
              "shell", "vinewtonrsls", "vinewtonssls")
KSP_TYPES = ("bcgs", "bcgsl", "bicg", "cg", "cgls", "cgne", "cgs", "chebyshev", "cr", "dgmres",
             "fbcgs", "fbcgsr", "fcg", "fetidp", "fgmres", "gcr", "gltr", "gmres", "groppcg", "hpddm",
             "ibcgs", "lcd", "lgmres", "lsqr", "minres", "nash", "none", "pgmres", "pipebcgs",
             "pipecg", "pipecg2", "pipecgrr", "pipecr", "pipefcg", "pipefgmres", "pipegcr",
             "pipelcg", "pipeprcg", "preonly", "python", "qcg", "qmrcgs", "richardson", "stcg",
             "symmlq", "tcqmr", "tfqmr", "tsirm")
PC_TYPES = ("asm", "bddc", "bfbt", "bjacobi", "cholesky", "chowiluviennacl", "composite", "cp",
            "deflation", "eisenstat", "exotic", "fieldsplit", "galerkin", "gamg", "gasm", "h2opus",
            "hmg", "hpddm", "hypre", "icc", "ilu", "jacobi", "kaczmarz", "ksp", "lmvm", "lsc", "lu",
            "mat", "mg", "ml", "nn", "none", "parms", "patch", "pbjacobi", "pfmg", "python", "qr",
            "redistribute", "redundant", "rowscalingviennacl", "saviennacl", "shell", "sor", "spai",
            "svd", "syspfmg", "telescope", "tfs", "vpbjacobi")
SOLVER_TYPES = ("bas", "cholmod", "cuda", "cusparse", "elemental", "essl", "klu", "lusol", "matlab",
                "mkl_cpardiso", "mkl_pardiso", "mumps", "pastix", "petsc", "scalapack",
                "sparseelemental", "spqr", "strumpack", "superlu", "superlu_dist", "umfpack")
ORDERING_TYPES = ("1wd", "amd", "external", "metisnd", "natural", "nd", "qmd", "rcm", "rowlength",
                  "spectral", "wbm")
LINESEARCH_TYPES = ("basic", "bt", "cp", "l2", "ncglinear", "nleqerr", "none", "shell")

#: registry types (case-sensitive, as PetscFunctionListFind compares them)
TYPES = {
    "snes_type": SNES_TYPES, "ksp_type": KSP_TYPES, "pc_type": PC_TYPES,
    "snes_linesearch_type": LINESEARCH_TYPES, "pc_factor_mat_solver_type": SOLVER_TYPES,
    "pc_factor_mat_ordering_type": ORDERING_TYPES,
    "pc_hypre_type": ("ads", "ams", "boomeramg", "euclid", "parasails", "pilut"),
    "pc_gamg_type": ("agg", "classical", "geo"),
}
#: enum values (case-insensitive, as PetscEListFind compares them)
ENUMS = {
    "ksp_norm_type": ("none", "preconditioned", "unpreconditioned", "natural"),
    "pc_factor_shift_type": ("none", "nonzero", "positive_definite", "inblocks"),
    "pc_asm_type": ("none", "basic", "restrict", "interpolate"),
    "pc_side": ("left", "right", "symmetric"),
}
#: reals with the smallest value that makes sense (PETSc parses them with strtod)
REALS = {
    "snes_rtol": 0.0, "snes_atol": 0.0, "snes_stol": 0.0, "snes_divergence_tolerance": None,
    "snes_linesearch_damping": 0.0, "snes_linesearch_maxstep": 0.0, "snes_linesearch_minlambda": 0.0,
    "snes_linesearch_rtol": 0.0, "snes_linesearch_atol": 0.0, "snes_linesearch_ltol": 0.0,
    "ksp_rtol": 0.0, "ksp_atol": 0.0, "ksp_divtol": None, "pc_factor_shift_amount": 0.0,
    "pc_factor_zeropivot": 0.0, "pc_factor_fill": 0.0, "pc_hypre_boomeramg_strong_threshold": 0.0,
}
#: reals PETSc's Set...Tolerances refuse from this value up ("Relative tolerance 1. must be
#: non-negative and less than 1.0"): -snes_rtol 1 ran a level, then stopped in a traceback, exit 1
REALS_BELOW = {"snes_rtol": 1.0, "ksp_rtol": 1.0}
#: integers with the smallest value that makes sense (PETSc parses them with strtol)
INTS = {
    "snes_max_it": 0, "snes_max_funcs": -1, "snes_max_fail": 0, "snes_max_linear_solve_fail": 0,
    "snes_lag_jacobian": -2, "snes_lag_preconditioner": -2, "snes_linesearch_max_it": 0,
    "ksp_max_it": 0, "ksp_gmres_restart": 1, "pc_factor_levels": 0, "pc_asm_overlap": 0,
    "pc_bjacobi_blocks": 1, "pc_gamg_agg_nsmooths": 0, "pc_mg_levels": 1,
    "pc_hypre_boomeramg_max_iter": 1, "pc_hypre_boomeramg_max_levels": 1,
}
BOOLS = ("ksp_initial_guess_nonzero", "snes_ksp_ew", "snes_mf", "snes_mf_operator",
         "ksp_error_if_not_converged", "snes_error_if_not_converged", "pc_factor_reuse_ordering",
         "pc_factor_reuse_fill", "ksp_gmres_modifiedgramschmidt", "pc_gamg_repartition",
         "pc_gamg_reuse_interpolation", "pc_jacobi_fixdiagonal", "options_left")
#: monitors and viewers: PETSc reads their value as a viewer, ``type[:file[:format[:mode]]]``
#: (PetscOptionsGetViewer), never as a boolean: ``-snes_monitor false`` stops the solve with
#: "Unsupported viewer false" (PETSc 3.18 and later alike); tests/apps/test_monitor_options.py checks that
#: PETSc reads each of these as a viewer
VIEWERS = ("snes_monitor", "snes_monitor_short", "snes_monitor_solution", "snes_monitor_residual",
           "snes_monitor_solution_update", "snes_linesearch_monitor", "snes_converged_reason",
           "snes_view", "snes_view_pre", "ksp_monitor", "ksp_monitor_short", "ksp_monitor_true_residual",
           "ksp_monitor_singular_value", "ksp_converged_reason", "ksp_view", "ksp_view_pre",
           "ksp_view_mat", "ksp_view_pmat", "ksp_view_rhs", "ksp_view_solution", "mat_view",
           "log_view")
#: the viewer types PetscOptionsGetViewer (3.18) takes as a whole value (no ':', no file name)
VIEWER_TYPES = ("ascii", "binary", "draw", "socket", "matlab", "saws", "vtk", "hdf5", "glvis",
                "exodusii")

#: options PETSc reads only while it starts (PetscInitialize), before ancf-solve reads the config:
#: under ``petsc:`` they did nothing and were reported as misspelt; refused there (config/solving.py)
START_UP_OPTIONS = ("help", "version", "info", "log_trace", "malloc_debug", "on_error_abort",
                    "no_signal_handler", "options_file", "skip_petscrc", "fp_trap")
#: options PETSc reads when it finishes (PetscFinalize): the config's value is put into the
#: database for the rest of the process (linalg/logging.view_at_exit), not around a solve
AT_FINISH_OPTIONS = ("log_view", "options_left")

#: prefixes under which the same option names appear (block, multigrid and split solvers)
PREFIX = re.compile(r"^(?:(?:sub|mg_coarse|mg_levels(?:_\d+)?|fieldsplit_\w+?|redundant|ksp)_)+")
_ONE_PREFIX = re.compile(r"^(?:sub|mg_coarse|mg_levels(?:_\d+)?|fieldsplit_[A-Za-z0-9]+|redundant|ksp)_")

_SPECIAL_REAL = ("petsc_default", "default", "petsc_decide", "decide")
_SPECIAL_INT = _SPECIAL_REAL + ("mouse",)
# C strtod (decimal, hexadecimal, inf, nan) and strtol base 10, each over the whole string;
# leading white space is skipped by both, trailing text makes PETSc reject the value
_STRTOD = re.compile(r"""\s*[+-]?(?:
    (?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?
  | 0[xX](?:[0-9a-fA-F]+\.?[0-9a-fA-F]*|\.[0-9a-fA-F]+)(?:[pP][+-]?\d+)?
  | inf(?:inity)? | nan(?:\([0-9A-Za-z_]*\))? )""", re.VERBOSE | re.IGNORECASE)
_STRTOL = re.compile(r"\s*[+-]?\d+")
_TRUE = ("", "true", "yes", "1", "on")
_FALSE = ("false", "no", "0", "off")


def parse_real(text: str) -> float | None:
    """The value PETSc's PetscOptionsStringToReal gives ``text``, or None if it rejects it
    (DEFAULT/DECIDE are returned as nan: PETSc's own placeholders)."""
    if text.strip().lower() in _SPECIAL_REAL and text == text.strip():
        return float("nan")
    if not text or not _STRTOD.fullmatch(text):
        return None
    s = text.strip().lower()
    if s.lstrip("+-").startswith("0x"):
        sign = -1.0 if s.startswith("-") else 1.0
        return sign * float.fromhex(s.lstrip("+-"))
    if "nan" in s:
        return float("nan")
    return float(s.replace("infinity", "inf"))


def parse_int(text: str) -> int | None:
    """PetscOptionsStringToInt: a base-10 integer over the whole string (no '.', no exponent)."""
    if text.lower() in _SPECIAL_INT:
        return -1
    if not text or not _STRTOL.fullmatch(text):
        return None
    return int(text.strip())


def parse_bool(text: str) -> bool | None:
    """PetscOptionsStringToBool: true/yes/1/on (or no value), false/no/0/off; any case."""
    t = text.lower()
    return True if t in _TRUE else (False if t in _FALSE else None)


def _bases(name: str) -> list[str]:
    """``name`` and what is left after each prefix in turn (``sub_ksp_type``: also ``ksp_type``;
    stripping every prefix at once would leave ``type``)."""
    out = [name]
    while (m := _ONE_PREFIX.match(out[-1])) and m.end() < len(out[-1]):
        out.append(out[-1][m.end():])
    return out


def _kind(name: str) -> tuple[str, str]:
    """(kind, base name) of an option name without its dash, in any case (PETSc's names ignore
    it: -SNES_RTOL abc passed the checks); kind '' = not checked."""
    for key in _bases(name.lower()):
        if key in TYPES:
            return "type", key
        if key in ENUMS:
            return "enum", key
        if key in REALS or re.fullmatch(r"mat_mumps_cntl_\d+", key):
            return "real", key
        if key in INTS or re.fullmatch(r"mat_mumps_icntl_\d+", key):
            return "int", key
        if key in BOOLS:
            return "bool", key
        if key in VIEWERS:
            return "viewer", key
    return "", name


def option_kind(name: str) -> str:
    """'type', 'enum', 'real', 'int', 'bool', 'viewer', or '' (not checked) for an option name
    without its dash."""
    return _kind(name)[0]


def check_value(name: str, value: str | None) -> str | None:
    """Why PETSc would reject ``value`` for option ``name`` (no leading dash), or None.

    ``value`` None means the option is given without a value (``-snes_monitor``)."""
    kind, base = _kind(name)
    if not kind:
        return None
    if kind == "bool":
        if value is None or parse_bool(value) is not None:
            return None
        return f"expected a boolean (true/false, yes/no, on/off, 1/0); got {value!r}"
    if kind == "viewer":
        return None if value is None or value == "" else _check_viewer(value)
    if value is None or value == "":
        what = {"type": "a type name", "enum": "one of " + ", ".join(ENUMS.get(base, ())),
                "real": "a number", "int": "an integer"}[kind]
        return f"needs a value: {what}"
    if kind == "type":
        if value in NEEDS_CODE.get(base, ()):
            return (f"{base.rsplit('_', 1)[0]} type {value!r} needs setup code that ancf-solve does not "
                    f"provide (sub-solvers or a user routine); use one of " + ", ".join(_COMMON[base]))
        if value in TYPES[base]:
            return None
        near = [t for t in TYPES[base] if t.lower() == value.lower()]
        hint = f" (type names are lower case: {near[0]})" if near else ""
        return f"unknown {base.rsplit('_', 1)[0]} type {value!r}{hint}; PETSc 3.18 has " \
               + ", ".join(_common(base))
    if kind == "enum":
        if value.lower() in ENUMS[base]:
            return None
        return f"expected one of {', '.join(ENUMS[base])}; got {value!r}"
    if kind == "real":
        x = parse_real(value)
        if x is None:
            return f"expected a number (PETSc reads it with strtod); got {value!r}"
        lo = REALS.get(base, None)
        if lo is not None and x == x and x < lo:
            return f"must be >= {lo:g}; got {value}"
        hi = REALS_BELOW.get(base)
        if hi is not None and x == x and x >= hi:
            return f"a relative tolerance must be below {hi:g} (PETSc refuses it); got {value}"
        return None
    n = parse_int(value)
    if n is None:
        return f"expected an integer (PETSc reads it with strtol: no '.' or exponent); got {value!r}"
    lo = INTS.get(base, None)
    if lo is not None and value.lower() not in _SPECIAL_INT and n < lo:
        return f"must be >= {lo}; got {value}"
    return None


def _check_viewer(value: str) -> str | None:
    """Why PetscOptionsGetViewer would refuse ``value``, or None.  Only a value without ':' is
    checked (its type is matched by suffix, as PETSc does); a ``type:file...`` value is PETSc's."""
    if parse_bool(value) is not None:
        return (f"a monitor or viewer takes no true/false: PETSc reads {value!r} as a viewer and stops "
                f"('Unsupported viewer {value}'); to turn it off leave the option out, to turn it on "
                "give it without a value (in the config: true) or a viewer such as ascii:FILE.txt")
    if ":" in value or value.endswith(VIEWER_TYPES):
        return None
    return (f"unknown viewer {value!r}; give no value (standard output) or "
            "ascii[:FILE[:FORMAT[:MODE]]], binary[:FILE], draw or hdf5:FILE")


def _is_key(token: str) -> bool:
    """PetscOptionsValidKey: one or two dashes and a letter (``-5`` is a value)."""
    t = token[1:] if token.startswith("--") else token
    return t.startswith("-") and len(t) > 1 and t[1].isalpha()


def command_line_options(args: list[str]) -> list[tuple[str, str | None]]:
    """(name without dashes, value or None) pairs as PETSc reads a command line."""
    out = []
    for i, tok in enumerate(args):
        if not _is_key(tok):
            continue
        value = args[i + 1] if i + 1 < len(args) and not _is_key(args[i + 1]) else None
        out.append((tok.lstrip("-"), value))
    return out


def stray_words(args: list[str]) -> list[str]:
    """The words of a command line that are neither an option nor its value, which PETSc skips
    without a word (``PetscOptionsInsertArgs``: an option takes the next word unless it is an
    option): a second config, ``snes_max_it 3`` without its dash, the 4 of ``-snes_max_it 3 4``."""
    out, i = [], 0
    while i < len(args):
        if not _is_key(args[i]):
            out.append(args[i])
            i += 1
        else:
            i += 2 if i + 1 < len(args) and not _is_key(args[i + 1]) else 1
    return out


def check_command_line(args: list[str]) -> str | None:
    """The first PETSc option on a command line that PETSc would reject, as one line."""
    for name, value in command_line_options(args):
        why = check_value(name, value)
        if why:
            return f"-{name}" + (f" {value}" if value is not None else "") + f": {why}"
    return None


#: types PETSc knows that cannot run without code of their own (composite/nasm/aspin: sub-solvers
#: set up in code; shell/python: a user's routine): refused before the solve, which failed with
#: "Must call SNESShellSetSolve() first" reported as a linear-solver failure (exit 3)
NEEDS_CODE = {"snes_type": ("aspin", "composite", "nasm", "patch", "python", "shell"),
              "snes_linesearch_type": ("shell",),
              # -pc_type shell: 'PETSC_ERROR in the linear solver ... No apply() routine provided
              # to Shell PC' at the first level (exit 3)
              "pc_type": ("python", "shell"), "ksp_type": ("python",)}

_COMMON = {
    "snes_type": ("newtonls", "newtontr", "vinewtonrsls", "qn", "ksponly"),
    "ksp_type": ("preonly", "gmres", "fgmres", "cg", "minres", "bcgs"),
    "pc_type": ("cholesky", "lu", "ilu", "icc", "gamg", "hypre", "jacobi", "bjacobi", "asm", "none"),
    "snes_linesearch_type": ("basic", "bt", "l2", "cp", "nleqerr"),
    "pc_factor_mat_solver_type": ("mumps", "superlu_dist", "petsc", "superlu"),
}


def _common(base: str) -> tuple[str, ...]:
    """The types worth naming in a message (all of them for short lists)."""
    return _COMMON.get(base, TYPES[base]) + (("...",) if base in _COMMON else ())
