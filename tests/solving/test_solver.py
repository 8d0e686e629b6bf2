"""Assembled residual/Jacobian, inverted elements, solver failures and PETSc option handling."""
import os

import h5py
import numpy as np
import pytest

from helpers import CONFIGS, FAILURE_MESSAGE, build_problem as _problem, jacobian_and_difference, load_raw, perturbed_state, petsc_init, read_summary, run_inline, solve_cli, two_beam_twisted, write_config


def test_assembled_jacobian_matches_finite_differences():
    P, PETSc = _problem(two_beam_twisted())
    P.load_factor = 0.7
    rng = np.random.default_rng(0)
    X, free = perturbed_state(P, rng, 2e-3)
    J = P.J
    P.jacobian(None, X, J, J)
    for _ in range(3):
        v = X.duplicate()
        v.setArray(rng.standard_normal(X.getLocalSize()) * free)
        jv, fd, _, _ = jacobian_and_difference(P, X, v)
        assert np.abs(jv - fd)[free].max() <= 1e-6 * np.abs(jv).max()
    # symmetric (energy) Jacobian
    Jd = J.convert("dense", PETSc.Mat()).getDenseArray()
    assert np.abs(Jd - Jd.T).max() <= 1e-10 * np.abs(Jd).max()


def test_residual_is_gradient_of_objective():
    P, PETSc = _problem(two_beam_twisted())
    P.load_factor = 0.3
    rng = np.random.default_rng(1)
    X, free = perturbed_state(P, rng, 1e-3)
    F = X.duplicate()
    P.residual(None, X, F)
    v = X.duplicate()
    v.setArray(rng.standard_normal(X.getLocalSize()) * free)
    h = 1e-6
    Xp, Xm = X.copy(), X.copy()
    Xp.axpy(h, v)
    Xm.axpy(-h, v)
    dPi = (P.objective(None, Xp) - P.objective(None, Xm)) / (2 * h)
    assert dPi == pytest.approx(F.dot(v), rel=1e-6)


def compression_case(tmp_path, force, steps, cutbacks=12, material=None):
    raw = load_raw("uniaxial_neohookean.yaml")
    if material:
        raw["beams"][0]["material"] = material
    raw["geometry"]["length"] = 0.01           # stocky: no Euler buckling
    raw["beams"][0]["elements"] = 2
    raw["loads"][0]["traction_force"] = [force, 0.0, 0.0]
    raw["steps"] = steps
    # these tests are about the step control: at ~58 % compression the states reached are
    # saddles (2-7 negative tangent eigenvalues, depending on the path), accepted here; straight
    # Newton steps (turned ones are held to a turn of 0.1, and no iterate inverts)
    raw["solver"] = {"max_cutbacks": cutbacks, "allow_unstable": True, "section_update": "linear"}
    raw["output"]["dir"] = str(tmp_path / "out")
    return raw


@pytest.mark.parametrize("guard", [0.0, 0.1], ids=["nan-cutback", "step-guard"])
def test_inverted_element_makes_the_step_back_off(tmp_path, guard):
    # one increment to ~58 % compression: the first Newton iterate would invert elements.
    # Without the guard the NaN residual cuts the load step back; with it (the default) Newton
    # steps are shortened so that det F stays above 0.1.
    raw = compression_case(tmp_path, -400.0, [1.0])
    raw["solver"]["min_det_f"] = guard
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"))
    assert p.returncode == 0, p.stderr
    if guard == 0.0:
        assert "inverted element" in p.stdout
    s = read_summary(tmp_path / "out")
    assert s["status"] == "completed" and s["steps"][0]["cutbacks"] >= 1
    assert s["steps"][0]["probes"]["tip"]["displacement"][0] < -0.005


def test_failure_names_load_and_reason_and_keeps_converged_steps(tmp_path):
    # SVK in uniaxial compression has a limit point at P = -E/(3 sqrt 3): 1.0 is beyond it
    raw = compression_case(tmp_path, -100.0, [0.05, 0.1, 1.0], cutbacks=3,
                           material={"model": "svk", "E": 3.0e6, "nu": 0.0})
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"))
    assert p.returncode == 3, p.stdout + p.stderr
    assert "Traceback" not in p.stderr
    msg = p.stderr.strip().splitlines()[-1]
    assert "could not reach load factor 1" in msg and "DIVERGED" in msg and "SNES failed at load factor" in msg
    s = read_summary(tmp_path / "out")
    assert s["status"] == "failed" and [st["load_factor"] for st in s["steps"]] == [0.05, 0.1]
    with h5py.File(tmp_path / "out" / "results.h5") as h5:
        assert sorted(h5["steps"]) == ["step_0001", "step_0002"]
        assert h5["steps/step_0002"].attrs["load_factor"] == 0.1
    assert os.path.exists(tmp_path / "out" / "surface_0002.vtu")


def test_newton_budget_stops_a_run_cleanly(tmp_path):
    """solver.max_newton_iterations: the run stops with a one-line message naming the budget;
    the levels reached before it stay on disk."""
    raw = load_raw("bending_neohookean.yaml")
    raw["solver"] = {"max_newton_iterations": 12}
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"))
    assert p.returncode == 3, p.stdout + p.stderr
    msg = p.stderr.strip().splitlines()[-1]
    assert "NEWTON_BUDGET_EXCEEDED after 13 Newton iterations (solver.max_newton_iterations = 12)" in msg, msg
    s = read_summary(tmp_path / "out")
    assert s["status"] == "failed" and FAILURE_MESSAGE.match(s["message"])
    assert 1 <= len(s["steps"]) < 4 and s["newton_iterations"] > 12


def test_an_atol_below_the_rounding_floor_is_named_not_taken_for_a_jump(tmp_path):
    """-snes_atol below 20 x the residual's rounding floor cannot be met: the failure names it
    (it was blamed on a 2.4e-11 N 'discontinuity of the discrete model, please report it')."""
    raw = load_raw("bending_neohookean.yaml")          # floor 4.9e-11 N
    raw["steps"] = [0.25]
    raw["solver"] = {"max_cutbacks": 1}
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["-snes_atol", "1e-15"])
    assert p.returncode == 3, p.stdout + p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert "(-snes_atol 1.0e-15, given in the run's options, is below 20 x the residual's rounding floor" in line, line
    assert "leave -snes_atol out or give at least" in line and "discontinuity" not in line, line
    assert read_summary(tmp_path / "out")["failure_cause"] == "unreachable_tolerance"


def test_a_newton_budget_caps_a_long_friction_solve(tmp_path):
    """The budget was checked between solves only: a friction column (a solve may take 200
    iterations) given 20 stopped after 35, a friction history given 110 after 197.  Each solve's
    -snes_max_it is now capped at what is left of it: the run stops at the budget plus one."""
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
        b["elements"] = 2
    raw["contact"] = {"mode": "sliding", "tangential": {"law": "coulomb", "friction": 0.3}}
    raw["steps"] = [100.0, 200.0, 300.0, 400.0]
    raw["solver"] = {"max_newton_iterations": 20}
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"))
    assert p.returncode == 3 and "NEWTON_BUDGET_EXCEEDED after 21 Newton iterations" in p.stderr, p.stderr


@pytest.mark.parametrize("snes_type", ["ksponly", "ms"])
def test_a_snes_type_that_keeps_no_residual_norm_is_judged_on_the_residual(tmp_path, snes_type):
    """-snes_type ksponly (one linear step) and ms report |F| = 0 and CONVERGED_ITS: their levels
    were accepted, the run said completed with one linear step's answers (ksponly) or NaN (ms).
    Now |F(X)| decides: the levels are not reached, exit 3."""
    raw = load_raw("bending_neohookean.yaml")
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["-snes_type", snes_type, "--quiet"])
    assert p.returncode == 3, p.stdout + p.stderr
    s = read_summary(tmp_path / "out")
    assert s["status"] == "failed" and not s["steps"]


def test_a_vi_newton_type_runs_on_aij(tmp_path):
    """-snes_type vinewtonssls reduces the Jacobian to its free rows, which segfaulted on the
    default SBAIJ matrix (exit 59, summary.json left 'running'): such types get AIJ, and the run
    gives the default solver's answer."""
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.5, 1.0]
    raw["output"] = {"dir": str(tmp_path / "vi"), "vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["-snes_type", "vinewtonssls", "--quiet"])
    assert p.returncode == 0, p.stdout + p.stderr
    default = run_inline(raw, tmp_path / "default")
    a, b = read_summary(tmp_path / "vi")["steps"][-1], default["steps"][-1]
    assert np.allclose(a["probes"]["tip"]["displacement"], b["probes"]["tip"]["displacement"], rtol=1e-8, atol=1e-14)


def test_command_line_overrides_config_petsc_section(tmp_path):
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["petsc"] = {"snes_linesearch_type": "l2", "snes_max_it": 3}
    raw["output"]["dir"] = str(tmp_path / "out")
    cfg = write_config(raw, tmp_path / "c.yaml")
    p = solve_cli(cfg, extra=["-snes_linesearch_type", "bt", "-snes_monitor", "-log_view"])
    assert p.returncode == 0, p.stderr
    assert "line search bt" in p.stdout and "max_it 3" in p.stdout
    assert "SNES Function norm" in p.stdout
    for stage in ("ANCF setup", "ANCF load stepping", "ANCF assembly", "ANCF output"):
        assert stage in p.stdout
    s = read_summary(tmp_path / "out")
    assert "line search bt" in s["solver"]


def test_outputs_are_complete(tmp_path):
    raw = load_raw("pretwisted_bar.yaml")
    s = run_inline(raw, tmp_path)
    assert s["status"] == "completed" and len(s["steps"]) == 4
    step = s["steps"][-1]
    assert set(step["probes"]) == {"tip", "tip_r_y"} and len(step["probes"]["tip"]["displacement"]) == 3
    assert {"setup", "solve", "output", "total"} <= set(s["timings"])
    import meshio
    m = meshio.read(tmp_path / "surface_0004.vtu")
    assert {"displacement", "E_xx", "J"} <= set(m.point_data)
    assert np.all(m.point_data["J"] > 0.5)
    pvd = (tmp_path / "surface.pvd").read_text()
    assert pvd.count("<DataSet") == 5
    with h5py.File(tmp_path / "results.h5") as h5:
        q = h5["steps/step_0004/nodal_vectors"][()]
        q0 = h5["model/reference_nodal_vectors"][()]
        tip = h5["model/beams/bar/connectivity"][()][-1, -1]
        assert np.allclose(q[tip, 0] - q0[tip, 0], step["probes"]["tip"]["displacement"], rtol=1e-12)


def test_surface_fields_against_the_deformation_gradient_and_compressed_vtus(tmp_path):
    """The VTU's J and E_xx are det F and ½(FᵀF − I)_xx of F = qᵀG at every surface point (checked
    against numpy's LU determinant and the full FᵀF); output.vtk_compress: true writes
    zlib-compressed VTUs with the same data as false, and auto compresses from
    AUTO_COMPRESS_POINTS surface points on (this bar has fewer)."""
    import meshio
    from ancf_petsc.io.vtk import AUTO_COMPRESS_POINTS, SurfaceSampler, VtkSeries
    from ancf_petsc.physics.element3363 import SLOTS
    raw = load_raw("pretwisted_bar.yaml")
    data = {}
    for compress in (True, False, "auto"):
        raw["output"] = {"vtk_compress": compress}
        run_inline(raw, tmp_path / str(compress))
        vtu = tmp_path / str(compress) / "surface_0004.vtu"
        assert ('compressor="vtkZLibDataCompressor"' in vtu.read_text(errors="ignore")) == (compress is True)
        data[compress] = meshio.read(vtu).point_data
    for key in ("displacement", "E_xx", "J"):
        assert np.array_equal(data[True][key], data[False][key])
    big = np.zeros((AUTO_COMPRESS_POINTS, 3))
    for n, zlib in ((AUTO_COMPRESS_POINTS - 1, False), (AUTO_COMPRESS_POINTS, True)):
        VtkSeries(str(tmp_path)).write("surface", n, 0.0, big[:n], [("vertex", np.arange(n)[:, None])], {})
        assert ('compressor="vtkZLibDataCompressor"' in (tmp_path / f"surface_{n:04d}.vtu").read_text(errors="ignore")) == zlib
    with h5py.File(tmp_path / "True" / "results.h5") as h5:
        q = h5["steps/step_0004/nodal_vectors"][()]
    P, _ = _problem(raw)
    sampler = SurfaceSampler(P.model, 4)
    _, _, _, fields = sampler.mesh(q)
    J, Exx = [], []
    for beam, _, _, _, G, e_of, *_ in sampler.parts:
        F = np.matmul(np.swapaxes(q[beam.connectivity].reshape(-1, SLOTS, 3)[e_of], 1, 2), G)
        J.append(np.linalg.det(F))
        Exx.append(0.5 * (np.matmul(np.swapaxes(F, 1, 2), F)[:, 0, 0] - 1.0))
    J, Exx = np.concatenate(J), np.concatenate(Exx)
    assert np.abs(J - 1.0).max() > 1e-3 and np.abs(Exx).max() > 1e-3          # really deformed
    assert np.allclose(fields["J"], J, rtol=1e-12, atol=1e-14)
    assert np.allclose(fields["E_xx"], Exx, rtol=1e-12, atol=1e-14)
    assert np.allclose(data[False]["J"], J, rtol=1e-6) and np.allclose(data[False]["E_xx"], Exx, atol=1e-6)


@pytest.mark.parametrize("config,tol", [("pretwisted_bar.yaml", 1e-6), ("achilles_type3_psi45.yaml", 1e-5)])
def test_petsc_snes_test_jacobian_agrees(tmp_path, config, tol):
    """PETSc's own finite-difference check (-snes_test_jacobian) on the full assembled matrix."""
    from helpers import CONFIGS
    import re
    raw = load_raw(config)
    for b in raw["beams"]:
        if "file" in b["section"]:
            b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["steps"] = raw["steps"][:1]
    raw["solver"] = {"max_cutbacks": 0}
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    # one Jacobian only (the check itself costs one residual per column); the load step may
    # then stop, exit code 3, which is fine here
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["-snes_test_jacobian", "-snes_max_it", "1"],
                  timeout=300)
    assert p.returncode in (0, 3), p.stderr
    ratios = [float(m) for m in re.findall(r"\|\|J - Jfd\|\|_F/\|\|J\|\|_F = ([0-9.eE+-]+)", p.stdout)]
    assert ratios and max(ratios) < tol, ratios


def test_options_prefix_tunes_two_solves_in_one_process_apart(tmp_path):
    """solver.options_prefix: -a_… options reach the solve with prefix a_ only; the config's
    petsc: options are read under the prefix too, and leave no option behind."""
    from petsc4py import PETSc

    raw = load_raw("bending_neohookean.yaml")
    opts = PETSc.Options()
    already = set(opts.getAll())
    opts["a_snes_linesearch_type"] = "bt"
    try:
        runs = {}
        for prefix in ("a_", "b_"):
            r = dict(raw, solver={"options_prefix": prefix}, petsc={"snes_max_it": 20})
            runs[prefix] = run_inline(r, tmp_path / prefix)
        before = set(opts.getAll())
    finally:
        opts.delValue("a_snes_linesearch_type")
    assert "line search bt" in runs["a_"]["solver"] and "line search basic" in runs["b_"]["solver"]
    assert all("max_it 20" in s["solver"] for s in runs.values())
    assert all(s["status"] == "completed" for s in runs.values())
    u = np.asarray(runs["b_"]["steps"][-1]["probes"]["tip"]["displacement"])   # to Newton's tolerance
    assert np.abs(np.asarray(runs["a_"]["steps"][-1]["probes"]["tip"]["displacement"]) - u).max() \
        <= 1e-8 * np.abs(u).max()
    assert not runs["b_"]["unused_petsc_options"], runs["b_"]["unused_petsc_options"]
    assert before - already == {"a_snes_linesearch_type"}      # the prefixed config options are gone


def test_a_misspelt_option_under_the_options_prefix_is_reported_unused(tmp_path):
    """The check of the prefixed options' values read each one, which PETSc counts as a use:
    -c_snes_maxit with options_prefix c_ (as -study1_snes_maxit in a study) went unreported."""
    from petsc4py import PETSc
    raw = load_raw("bending_neohookean.yaml")
    raw["steps"] = [0.25]
    opts = PETSc.Options()
    opts["c_snes_maxit"] = "3"
    try:
        summary = run_inline(dict(raw, solver={"options_prefix": "c_"}), tmp_path / "c")
    finally:
        opts.delValue("c_snes_maxit")
    assert summary["status"] == "completed" and "max_it 15" in summary["solver"]
    assert summary["unused_petsc_options"] == ["-c_snes_maxit"], summary["unused_petsc_options"]


def test_a_failed_mumps_factorisation_says_what_to_change(tmp_path):
    """MUMPS's own error code (INFOG(1)) reaches the one-line failure with the option that
    cures it: a working-memory cap that is too small (-mat_mumps_icntl_23 1, INFOG(1) = -19);
    workspace-margin errors name ICNTL(14)."""
    from ancf_petsc.linalg.diagnostics import mumps_hint
    raw = load_raw("bundle_hex7.yaml")
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    raw["solver"] = {"max_cutbacks": 1}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["-mat_mumps_icntl_23", "1"])
    assert p.returncode == 3, p.stdout + p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert "INFOG(1) = -19" in line and "-mat_mumps_icntl_23" in line, line
    for code in (-8, -9, -17, -20):
        assert "-mat_mumps_icntl_14" in mumps_hint(code)


def test_chord_steps_keep_every_newton_count_and_answer(tmp_path):
    """solver.reuse_tangent (solving/chord.py): on the ψ = 45° Achilles column some levels end
    with a step on the previous iterate's factored tangent.  Against a fresh tangent at every
    step: the same Newton iterations per level and stability verdicts, probes within 1e-9, and
    PETSc factored exactly the iterations less the reuses (PCSetUp kept the factor)."""
    petsc_init()
    from petsc4py import PETSc
    from ancf_petsc.linalg.logging import event_count
    PETSc.Log.begin()
    raw = load_raw("achilles_type3_psi45.yaml")
    runs = {}
    for reuse in (False, True):
        raw["solver"] = {"reuse_tangent": reuse}
        before = event_count("MatCholFctrNum")
        s = run_inline(raw, tmp_path / str(reuse))
        runs[reuse] = (s, event_count("MatCholFctrNum") - before)
    (plain, plain_factors), (chord, chord_factors) = runs[False], runs[True]
    assert plain["tangent_reuses"] == 0 and plain_factors == plain["newton_iterations"]
    assert chord["tangent_reuses"] >= 4
    assert chord_factors == chord["newton_iterations"] - chord["tangent_reuses"]
    assert [st["iterations"] for st in chord["steps"]] == [st["iterations"] for st in plain["steps"]]
    assert [st["negative_eigenvalues"] for st in chord["steps"]] == [0] * len(plain["steps"])
    for a, b in zip(plain["steps"], chord["steps"]):
        for name in a["probes"]:
            assert np.allclose(b["probes"][name]["displacement"], a["probes"][name]["displacement"],
                               rtol=1e-9, atol=1e-9 * 6e-3)


def test_chord_rule_from_the_third_iterate_never_twice_and_on_its_estimate():
    """chord.TangentReuse: the estimate 2‖F_k‖²/‖F_k−1‖ against a tenth of the tolerance, only
    from the third iterate of a solve, never twice in a row, never after a step that raised the
    residual, off when disabled."""
    from ancf_petsc.solving.chord import TangentReuse
    atol, rtol = 4e-8, 1e-10
    rule = TangentReuse(True)
    rule.start_solve()
    assert not rule.decide([1.0], atol, rtol)                       # first iteration
    assert not rule.decide([1.0, 1e-5], atol, rtol)                 # second: ‖F_0‖ is the load's
    assert not rule.decide([1.0, 1e-2, 1e-5], atol, rtol)           # estimate 2e-8 > 4e-9
    assert rule.decide([1.0, 1e-2, 1e-6], atol, rtol)               # estimate 2e-10
    assert not rule.decide([1.0, 1e-2, 1e-6, 1e-12], atol, rtol)    # not twice in a row
    assert rule.decide([1.0, 1e-2, 1e-6, 1e-9, 1e-15], atol, rtol)  # after a Newton step again
    assert rule.count == 2
    rule.start_solve()
    assert rule.decide([1.0, 1e-2, 1e-6], atol, rtol)               # a new solve
    rule.start_solve()
    assert rule.decide([1e6, 1e-2, 1e-5], atol, rtol)               # tolerance rtol ‖F_0‖ = 1e-4
    rule.start_solve()                     # a walking-stride frame: the step before raised |F|
    assert not rule.decide([24.1, 0.06, 0.243, 6.2e-6], 2.2e-7, rtol)
    assert rule.decide([24.1, 0.06, 0.0243, 6.2e-6], 2.2e-7, rtol)
    off = TangentReuse(False)
    assert not off.decide([1.0, 1e-2, 1e-6], atol, rtol) and off.count == 0


@pytest.mark.parametrize("mode, extra, expect", [
    ("sliding", ["-ksp_type", "gmres", "-pc_type", "bjacobi", "-ksp_max_it", "200"], "saddle-point matrix"),
    ("sliding", ["-pc_type", "none"], "solves nothing"),
    ("unilateral", ["-snes_max_it", "1"], "(-snes_max_it 1, given in the run's options, is below the run's "
                                          "own 60: the solve ran out of the iterations given; leave it out"),
])
def test_failure_hints_for_contact_models(tmp_path, mode, extra, expect):
    """Issue 25: a contact model is not told to use gmres with gamg/bjacobi (they fail on its
    saddle-point Jacobian); -pc_type none and a short Newton budget under unilateral contact get
    a hint of their own."""
    raw = load_raw("bundle_hex7.yaml")
    raw["contact"]["mode"] = mode
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    raw["solver"] = {"max_cutbacks": 0}
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=extra)
    assert p.returncode == 3, p.stdout + p.stderr
    line = p.stderr.strip().splitlines()[-1]
    assert expect in line, line
    assert "-ksp_type gmres with -pc_type gamg" not in line


def test_a_friction_run_blames_a_small_newton_budget_and_names_a_command_line_pc(tmp_path):
    """With friction -snes_max_it 3 ran out and the message blamed the stick-slip statuses and μ
    (μ = 0.3, which the run's own 200 solve); -pc_type cholesky on the command line was named
    petsc.pc_type, a config key the config did not have."""
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
        b["elements"] = 2
    raw["contact"] = {"mode": "sliding", "tangential": {"law": "coulomb", "friction": 0.3}}
    raw["steps"] = [100.0]
    raw["output"] = {"dir": str(tmp_path / "out"), "vtk": False}
    cfg = write_config(raw, tmp_path / "c.yaml")
    p = solve_cli(cfg, extra=["-snes_max_it", "3"])
    line = p.stderr.strip().splitlines()[-1]
    assert p.returncode == 3 and "(-snes_max_it 3, given in the run's options, is below the run's own 200" in line
    assert "stick-slip" not in line, line
    p = solve_cli(cfg, extra=["-pc_type", "cholesky"])
    assert p.returncode == 2 and "config error: -pc_type: cholesky factors a symmetric matrix" in p.stderr, p.stderr


@pytest.mark.parametrize("last,substeps", [(2.5, 1), (2.6, 2)])
def test_the_rest_of_the_way_to_a_level_up_to_stretch_increments_is_one_step(last, substeps, tmp_path):
    """No sliver step: from 1.0 with increments of 1.0 (no growth) the level 2.5 is reached in
    one step (1.5 increments, ``load_control.STRETCH``), 2.6 in an increment and the rest."""
    from ancf_petsc.solving.load_control import STRETCH
    assert STRETCH == 1.5
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["steps"] = [0.1, 0.1 * last]
    raw["solver"] = {"initial_increment": 0.1, "growth": 1.0}
    s = run_inline(raw, tmp_path)
    assert s["status"] == "completed"
    assert [st["substeps"] for st in s["steps"]] == [1, substeps]


def test_a_workflows_solves_each_get_their_own_options_prefix(tmp_path):
    """In-process solves of a workflow (here ancf-study's ``solve_raw``) run under their own
    prefix (linalg.database.own_prefix): the solver options given without a prefix still reach
    every solve, the config's ``petsc:`` options reach only their solve, and nothing is left in
    the database afterwards; a prefix the config gives is kept."""
    from petsc4py import PETSc

    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.linalg.database import own_prefix, option_names
    from ancf_petsc.workflows.study import solve_raw
    from helpers import CONFIGS

    raw = load_raw("bending_neohookean.yaml")
    opts = PETSc.Options()
    already = set(opts.getAll())
    opts["snes_linesearch_type"] = "bt"                  # as if on the command line
    try:
        first, s1 = solve_raw(dict(raw, petsc={"snes_max_it": 20}), CONFIGS, str(tmp_path / "1"))
        second, s2 = solve_raw(raw, CONFIGS, str(tmp_path / "2"))
        after = set(option_names())
    finally:
        opts.delValue("snes_linesearch_type")
    assert first.status == second.status == "completed"
    assert "line search bt" in s1["solver"] and "line search bt" in s2["solver"]
    assert "max_it 20" in s1["solver"] and "max_it 20" not in s2["solver"]
    assert after - already == {"snes_linesearch_type"}
    spec = parse_config(dict(raw, solver={"options_prefix": "mine_"}), base_dir=CONFIGS)
    with own_prefix(spec.solver, "study") as prefix:
        assert prefix == "mine_"
    spec = parse_config(raw, base_dir=CONFIGS)
    with own_prefix(spec.solver, "study") as p1:
        pass
    with own_prefix(spec.solver, "study") as p2:
        pass
    assert p1 != p2 and p1.startswith("study") and spec.solver.options_prefix == ""


def test_an_overflowing_trial_state_gives_a_nan_residual_without_warnings():
    """A GOH fibre stretched so far that e^(k2 Ē²) overflows (a wild trial iterate): the residual
    is NaN, which the line search backs off from, and numpy prints no RuntimeWarning (the runs
    of soft-matrix sets used to fill stderr with them)."""
    import warnings
    raw = load_raw("pretwisted_bar.yaml")
    raw["beams"][0]["material"] = {"model": "goh", "mu": 1.0e4, "bulk_modulus": 5.0e5, "k1": 1.0e6,
                                   "k2": 524.6, "kappa": 0.0, "fibres": {"follow": "twist"}}
    P, _ = _problem(raw)
    X = P.q0.copy()
    X.scale(3.0)                      # every gradient tripled: Ē = 8, k2 Ē² ~ 3e4
    F = X.duplicate()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        P.residual(None, X, F)
    assert np.all(np.isnan(F.getArray())) and P.inverted


#: |F| of the last failed solve of the tendon_model_2023 GOH column with sliding contact at
#: 81.34 N (-snes_monitor, 2026-11-26): a cycle of period 6
CYCLING = [3.9986e-02, 3.0666e-05, 4.106667e-02, 8.471389e-02, 2.003852e-02, 1.484979e-02, 8.362539e-04,
           9.967742e-05, 4.106672e-02, 8.471799e-02, 2.003861e-02, 1.485130e-02, 8.363446e-04, 9.970484e-05,
           4.106672e-02, 8.471799e-02]


#: ... and of the soleus-biased unilateral stride at ψ = 90°, frame 46.8 (2.35 kN; 2026-11-28): period
#: 5, drifting by up to 1.8e-3 per period
CYCLING_5 = [1.340833e+00, 7.801791e+00, 9.749213e+00, 2.712757e+00, 2.544255e-01, 1.346822e+00,
             7.627389e+00, 9.711299e+00, 2.641625e+00, 2.527476e-01, 1.346365e+00, 7.637708e+00,
             9.713286e+00, 2.646319e+00, 2.528854e-01, 1.346397e+00]


@pytest.mark.parametrize("history,expected", [
    (CYCLING, "cycles: |F| repeats every 6 iterations, between 1.0e-04 and 8.5e-02 N"),
    (CYCLING_5, "cycles: |F| repeats every 5 iterations, between 2.5e-01 and 9.7e+00 N"),
    ([2.2e-2, 1.5e-2, 3.6e-4, 1.2e-5] + [1.7090501e-08 * (1 + 1e-8 * k) for k in range(12)],
     "stalls at |F| 1.71e-08 N"),
    ([10.0 * 0.5 ** k for k in range(16)], "converges only linearly here, |F| x 0.50-0.50"),
    ([10.0 * 0.97 ** k for k in range(16)], "converges only linearly here, |F| x 0.97-0.97"),
    # the traced subject's sliding column at twist 120 deg, 2.57 kN (docs/gait.md): the last iterates
    ([1.0, 0.21, 0.11, 0.72, 0.12, 0.096, 0.16, 0.116, 0.36, 0.167, 0.363, 0.072, 0.104, 0.269, 0.069,
      0.157, 0.122], "iterates wander: |F| between 6.9e-02 and 3.6e-01 N over the last 7")],
    ids=["cycle", "cycle5", "stall", "converging", "slow", "wandering"])
def test_a_failed_level_says_when_newton_cycles_or_stalls(history, expected):
    """A level that ran out of Newton iterations names a cycle or a stall (more iterations do not
    help) instead of suggesting a larger -snes_max_it; a Newton still converging says it converges
    only linearly, one that neither converges nor repeats that it wanders (both: a larger
    -snes_max_it may reach a state whose stability check names a limit point)."""
    from types import SimpleNamespace
    petsc_init()
    from petsc4py import PETSc
    from ancf_petsc.solving.solver_messages import failure_detail
    snes = PETSc.SNES().create(PETSc.COMM_SELF)
    try:
        solver = SimpleNamespace(snes=snes, last_solve_history=history, problem=SimpleNamespace(contact=None))
        text = failure_detail(solver, PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT)
        more = f"or -snes_max_it {3 * snes.getTolerances()[3]} may reach"
    finally:
        snes.destroy()
    assert expected in text, text
    helps = "linearly" in expected or "wander" in expected
    assert ("more iterations do not help" in text) != helps and (more in text) == helps, text
    kind = {"cycles": "newton_cycle", "stalls": "newton_stall", "linearly": "newton_linear",
            "wander": "newton_wander"}
    assert text.kind == next(v for k, v in kind.items() if k in expected), text.kind   # failure_cause.py


def test_a_wandering_friction_solve_is_ended_early():
    """Friction's semi-smooth iteration that finds no new smallest |F| in WANDER_WINDOW iterations
    ends (DIVERGED_MAX_IT: the Tresca fixed point takes over) instead of running to its 200: the
    μ = 0.3 walking stride's frame 12 wandered between 1 and 750 N for 196 iterations after its
    best (1.03 N at the 4th).  A converging history, however slowly, and a short one do not."""
    from ancf_petsc.solving.cycle_stop import WANDER_WINDOW, wandering
    rng = np.random.default_rng(0)
    wander = [3.2, 1.6, 1.1, 1.6, 1.03] + list(1.5 + 5.0 * rng.random(WANDER_WINDOW))
    assert wandering(wander)
    assert not wandering(wander[:-1] + [1.0])                    # a new best in the window
    assert not wandering([10.0 * 0.97 ** k for k in range(3 * WANDER_WINDOW)])
    assert not wandering(wander[:WANDER_WINDOW])                 # too short to judge


def test_unilateral_contact_ends_a_solve_without_progress_after_its_window():
    """A unilateral law's solve may take -snes_max_it 60 (its default) while |F| finds new lows,
    and ends after ``wander_window`` (15) iterations without one: the stop rules of the model's
    contact (friction's window 40, unilateral 15, none without contact)."""
    from ancf_petsc.contact.laws import SlidingLaw, UnilateralLaw
    from ancf_petsc.solving.cycle_stop import WANDER_WINDOW, wandering
    from ancf_petsc.solving.snes_solver import stop_window

    class Contact:
        def __init__(self, law, bounded):
            self.law, self.terms = law, [type("Term", (), {"bounded": bounded})()]
    assert stop_window(None) is None
    assert stop_window(Contact(SlidingLaw(), False)) is None
    assert stop_window(Contact(UnilateralLaw(), False)) == (UnilateralLaw.wander_window, -1.0)  # divtol off
    assert UnilateralLaw.wander_window == 15
    assert stop_window(Contact(UnilateralLaw(), True)) == (WANDER_WINDOW, 1e4)
    stuck = [50.0, 9.0, 4.0] + [4.0 + k % 3 for k in range(15)]
    assert wandering(stuck, 15) and not wandering(stuck[:-1], 15)
    slow = [50.0 * 0.9 ** k for k in range(60)]                 # a new low at every iteration
    assert not wandering(slow, 15)


def test_a_unilateral_solve_ended_by_its_window_says_so():
    """The failure of a unilateral level whose last solve the window ended names the smallest |F|
    and the window, and the pointwise fade forces when the config chose variational ones (with
    auto the run switched where it could), not the advice to raise -snes_max_it (which stays for
    a solve that ran all its iterations finding new lows)."""
    from types import SimpleNamespace
    from petsc4py import PETSc
    from ancf_petsc.contact.laws import UnilateralLaw
    from ancf_petsc.solving.cycle_stop import CycleStop
    from ancf_petsc.solving.solver_messages import failure_detail
    snes = PETSc.SNES().create(comm=PETSc.COMM_SELF)
    snes.setTolerances(max_it=60)
    history = [50.0, 9.0, 4.0] + [4.0 + k % 7 for k in range(15)]
    stop = CycleStop(lambda: history, {}, "", 15, -1.0)
    contact = SimpleNamespace(law=UnilateralLaw(), terms=[], weights=SimpleNamespace(variational=True, rule="newton"),
                              spec=SimpleNamespace(fade_forces="variational"))
    solver = SimpleNamespace(snes=snes, problem=SimpleNamespace(contact=contact), cycle_stop=stop,
                             last_solve_history=history)
    reason = PETSc.SNES.ConvergedReason.DIVERGED_MAX_IT
    stop.wandered = True
    assert "found no |F| below 4.00e+00 N in its last 15 iterations" in failure_detail(solver, reason)
    assert failure_detail(solver, reason).kind == "newton_wander"
    assert "contact.fade_forces: auto or pointwise" in failure_detail(solver, reason)    # the way out
    contact.spec.fade_forces = "auto"               # switched where it could, or refused on a saddle
    assert "fade_forces" not in failure_detail(solver, reason)
    contact.spec.fade_forces = "variational"
    contact.weights.variational, contact.weights.rule = True, "settle"    # never differentiated
    assert "fade_forces" not in failure_detail(solver, reason)
    stop.wandered = False
    assert "try -snes_max_it 240" in failure_detail(solver, reason)
    assert failure_detail(solver, reason).kind == "active_set_iterations"
    snes.destroy()
