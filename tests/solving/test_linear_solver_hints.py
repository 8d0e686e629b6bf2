"""What a failed level says about the linear solver the options chose: a preconditioner applied
once under -ksp_type preonly, and what to try after a Krylov method failed."""
import os
import re

import pytest

from helpers import CONFIGS, cantilever, load_raw, read_summary, solve_cli, write_config


@pytest.mark.parametrize("pc", ["jacobi", "gamg"])
def test_a_preconditioner_applied_once_is_named_not_a_limit_point(tmp_path, pc):
    """With the default -ksp_type preonly, -pc_type jacobi (or gamg) is applied once instead of
    solving the Newton equations.  The 2-element cantilever's failure read 'Newton's iterates
    wander ... as near a limit or bifurcation point' (gamg: 'Newton converges only linearly
    here ... a nearly singular tangent'), pointing at the model.  The step's linear residual
    |J y - F| / |F| is now measured at the failure and the option named."""
    raw = cantilever([0.5, 1.0], elements=2)
    raw["output"]["dir"] = str(tmp_path / "out")
    raw["solver"] = {"max_cutbacks": 0}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["-pc_type", pc, "--quiet"])
    assert p.returncode == 3, p.stdout + p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert f"(-pc_type {pc} with -ksp_type preonly is applied once instead of solving" in line, line
    assert "limit or bifurcation" not in line and "add -ksp_type gmres" in line
    share = float(re.search(r"\|J step - F\| = (\S+) \|F\|", line).group(1))
    assert share > 0.1                             # measured: jacobi 5.2, gamg 0.98
    assert read_summary(tmp_path / "out")["failure_cause"] == "linear_solver"


def test_on_a_contact_model_its_inverted_element_is_put_down_to_the_preconditioner(tmp_path):
    """-pc_type jacobi on the paper's tendon (1 element per subtendon): the steps inverted an
    element, and the failure said only 'with DIVERGED_FNORM_NAN (an element was inverted)'.  The
    residual there is not finite: the preconditioner is measured on J's own range instead."""
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["elements"] = 1
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw.update(steps=[10.0], solver={"max_cutbacks": 0}, output={"dir": str(tmp_path / "out"), "vtk": False})
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["-pc_type", "jacobi", "--quiet"])
    line = p.stderr.strip().splitlines()[-1]
    assert p.returncode == 3 and "with DIVERGED_FNORM_NAN (-pc_type jacobi with -ksp_type preonly is applied once" in line
    assert "saddle-point matrix" in line and "add -ksp_type gmres" not in line, line


def test_an_exact_preconditioner_under_preonly_is_not_blamed(tmp_path):
    """ILU(0) of a beam's banded tangent on one rank is its LU: the run completes as the default."""
    raw = cantilever([0.5, 1.0], elements=2)
    raw["output"]["dir"] = str(tmp_path / "out")
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["-pc_type", "ilu", "--quiet"])
    assert p.returncode == 0, p.stderr


def test_the_hint_after_a_failed_krylov_solve_names_other_preconditioners():
    """-ksp_type gmres -pc_type gamg broke down on the cantilever and was told to use
    '-ksp_type gmres with -pc_type gamg, hypre, bjacobi or asm'."""
    from ancf_petsc.linalg.diagnostics import solver_hint
    for pc in ("gamg", "hypre", "bjacobi", "asm"):
        krylov = solver_hint(pc, "", 1).split("-ksp_type gmres with -pc_type ")[1]
        assert pc not in krylov and len(krylov.split(",")) == 2, krylov
    assert solver_hint("jacobi", "", 1).endswith("-pc_type gamg, hypre, bjacobi or asm")
    assert solver_hint("jacobi", "", 1, lambda name: name != "hypre").endswith("-pc_type gamg, bjacobi or asm")


def test_a_krylov_budget_given_below_the_solvers_own_is_named(tmp_path):
    """-ksp_max_it 2 with the fascicle Schur solver (FGMRES, its own budget 100) on the 7-fascicle
    bundle: the failure said only 'solver.linear: direct factors the whole Jacobian instead'.
    (GMRES with -ksp_max_it 3 on the direct path: tests/apps/test_edges.py.)"""
    raw = load_raw("bundle_hex7.yaml")
    raw["bundle"]["elements"] = 2
    raw.update(steps=[0.5], output={"dir": str(tmp_path / "out"), "vtk": False},
               solver={"max_cutbacks": 0, "linear": "fieldsplit"})
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["-ksp_max_it", "2", "--quiet"])
    line = p.stderr.strip().splitlines()[-1]
    assert p.returncode == 3 and "stopped with DIVERGED_MAX_IT; -ksp_max_it 2, given in the run's options, " \
        "is below the linear solver's own 100" in line, line
    assert "solver.linear: direct factors the whole Jacobian instead" in line


def test_an_lu_only_package_with_the_default_cholesky_is_told_to_add_lu(tmp_path):
    """-pc_factor_mat_solver_type superlu alone (the default -pc_type cholesky) was refused with
    'superlu cannot do cholesky here: use ... -pc_type lu with -pc_factor_mat_solver_type mumps',
    not that -pc_type lu makes SuperLU run; with it the cantilever gets the default's tip."""
    from ancf_petsc.linalg.diagnostics import solver_hint
    assert "superlu_dist factors LU only: add -pc_type lu" in solver_hint("cholesky", "superlu_dist", 2)
    raw = cantilever([0.5], elements=2)
    raw["output"]["dir"] = str(tmp_path / "out")
    cfg = write_config(raw, tmp_path / "c.yaml")
    p = solve_cli(cfg, extra=["-pc_factor_mat_solver_type", "superlu", "--quiet"])
    assert p.returncode == 2 and "superlu factors LU only: add -pc_type lu" in p.stderr, p.stderr
    tips = []
    for extra in ([], ["-pc_factor_mat_solver_type", "superlu", "-pc_type", "lu"]):
        assert solve_cli(cfg, extra=extra + ["--quiet"]).returncode == 0
        tips.append(read_summary(tmp_path / "out")["steps"][-1]["probes"]["tip"]["displacement"])
    assert max(abs(a - b) for a, b in zip(*tips)) <= 1e-10 * max(abs(a) for a in tips[0])


@pytest.mark.parametrize("option, value", [("pc_type", "shell"), ("pc_type", "python"), ("ksp_type", "python"),
                                           ("sub_pc_type", "shell")])
def test_a_solver_type_that_needs_code_is_refused_before_the_run(tmp_path, option, value):
    """-pc_type shell ran to the first level and failed there, exit 3: 'PETSC_ERROR in the linear
    solver (-ksp_type preonly -pc_type shell): No apply() routine provided to Shell PC'."""
    raw = cantilever([0.5], elements=2)
    raw["output"]["dir"] = str(tmp_path / "out")
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=[f"-{option}", value, "--quiet"])
    kind = option.removeprefix("sub_").rsplit("_", 1)[0]
    assert p.returncode == 2 and f"-{option} {value}: {kind} type '{value}' needs setup code" in p.stderr, p.stderr
    assert not (tmp_path / "out" / "results.h5").exists()


def test_an_unprefixed_option_under_an_options_prefix_names_the_prefix(tmp_path):
    """With solver.options_prefix left_, -snes_max_it 3 is not read (the solver reads
    -left_snes_max_it) and was reported only as 'misspelt, or not read by the solver in use'."""
    raw = cantilever([0.5], elements=2)
    raw["output"]["dir"] = str(tmp_path / "out")
    raw["solver"] = {"options_prefix": "left_"}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["-snes_max_it", "3", "--quiet"])
    assert p.returncode == 0, p.stderr
    assert ("PETSc option -snes_max_it was never used: misspelt, or not read by the solver in use (the "
            "config's solver.options_prefix is left_: the solver reads -left_snes_max_it)") in p.stderr, p.stderr
    assert read_summary(tmp_path / "out")["tolerances"]["max_it"] == 15
