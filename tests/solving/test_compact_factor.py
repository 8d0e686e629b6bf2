"""The compact factorisation on one rank (linalg/compact_factor.py): MUMPS LDLᵀ of the
Jacobian's structural nonzeros gives the Newton step and the pivot counts of MUMPS on every
stored entry, grows its structure where a value appears outside it, fails the preconditioner as
MUMPS's own factorisation does, and leaves the paper's column unchanged."""
import numpy as np
import pytest

from helpers import hex7_problem, load_raw, petsc_init, read_summary, solve_cli, write_config, CONFIGS


@pytest.fixture(autouse=True)
def _no_mumps_option_left():
    """``_compact`` puts -mat_mumps_icntl_24 in PETSc's global database: taken out after each
    test, or later runs of the same process factor with it (tests/apps/test_edges.py's run whose
    MUMPS must give up on a singular tangent then found an unstable state instead)."""
    yield
    from petsc4py import PETSc
    PETSc.Options().delValue("mat_mumps_icntl_24")


def _mumps(PETSc, J, icntl24=True):
    from ancf_petsc.linalg.inertia import mumps_ldlt
    return mumps_ldlt(J, icntl24)


def _residual(J, x, b) -> float:
    r = b.duplicate()
    J.mult(x, r)
    r.axpy(-1.0, b)
    return r.norm()


def _backward_error(PETSc, J, x, b) -> float:
    """Normwise backward error of x for J x = b (Rigal–Gaches; Higham, Accuracy and Stability, Thm 7.1)."""
    r = b.duplicate()
    J.mult(x, r)
    r.axpy(-1.0, b)
    inf = PETSc.NormType.INFINITY
    return r.norm(inf) / (J.norm(inf) * x.norm(inf) + b.norm(inf))


def _compact(PETSc, P):
    from ancf_petsc.linalg.compact_factor import install, multiplier_mask
    ksp = PETSc.KSP().create(comm=PETSc.COMM_SELF)
    ksp.setOperators(P.J, P.J)
    ksp.setType("preonly")
    PETSc.Options()["mat_mumps_icntl_24"] = "1"
    ctx = install(ksp, P.fixed_mask, multiplier_mask(P))
    return ksp, ctx


def test_stored_entries_name_the_value_array_in_order():
    """Entry i of a sequential SBAIJ value array is J[rows[i], cols[i]] (blocks by columns)."""
    petsc_init()
    from petsc4py import PETSc
    from ancf_petsc.linalg.compact_factor import ValueArray, stored_entries
    rng = np.random.default_rng(3)
    D, nb = 3, 3
    A = rng.standard_normal((D * nb, D * nb))
    A = A + A.T
    A[:D, 2 * D:] = A[2 * D:, :D] = 0.0            # blocks (0, 2) and (2, 0) not stored
    J = PETSc.Mat().createSBAIJ(D * nb, D, nnz=3, comm=PETSc.COMM_SELF)
    J.setOption(PETSc.Mat.Option.IGNORE_LOWER_TRIANGULAR, True)
    for i in range(nb):
        for j in range(i, nb):
            if (i, j) != (0, 2):
                J.setValuesBlocked([i], [j], A[D * i:D * i + D, D * j:D * j + D])
    J.assemble()
    rows, cols = stored_entries(J)
    assert len(rows) == 5 * D * D
    upper = cols >= rows
    with ValueArray(J, len(rows)) as a:
        assert np.array_equal(a[upper], A[rows[upper], cols[upper]])
    J.destroy()


def test_the_compact_factor_gives_the_newton_step_and_the_pivots_of_mumps():
    """bundle_hex7 after a Newton step (multipliers non-zero: contact curvature): the same step
    to rounding, the same negative and null pivots, from fewer entries."""
    P, PETSc, F = hex7_problem(loaded=True, matrix="sbaij")
    plain = _mumps(PETSc, P.J)
    ksp, ctx = _compact(PETSc, P)
    x0, x1 = F.duplicate(), F.duplicate()
    plain.solve(F, x0)
    ksp.solve(F, x1)
    assert ksp.getConvergedReason() > 0
    # backward stable on every entry, as MUMPS is: the normwise backward error
    # |J x − F|∞ / (|J|∞ |x|∞ + |F|∞) below a few machine epsilons (MUMPS 7e-19 and 1e-17 on
    # one AMD EPYC, 2e-13 and 7e-13 of |F| = 0.064 on an Intel machine: the ratio of the two
    # residuals is the BLAS kernels' rounding, not a property); a dropped entry of J would leave
    # its share of |J| |x|.  The steps differ by 3e-9 (the saddle matrix's condition)
    for x in (x0, x1):
        assert _backward_error(PETSc, P.J, x, F) <= 4.0 * np.finfo(float).eps
    assert (x1 - x0).norm() <= 1e-7 * x0.norm()
    from ancf_petsc.linalg.inertia import pivot_counts
    F0 = plain.getPC().getFactorMatrix()
    assert pivot_counts(ksp) == (F0.getMumpsInfog(12), F0.getMumpsInfog(28))
    assert pivot_counts(ksp)[0] >= P.n_constraints > 0
    s = ctx.structure
    assert len(s.dropped) > 0 and len(s.src) < len(s.src) + len(s.dropped)
    # the held DOFs' off-diagonal entries and the multiplier-multiplier ones are gone
    rows, cols = s.indptr, s.indices
    r = np.repeat(np.arange(s.n), np.diff(rows))
    held = P.fixed_mask
    assert not np.any(held[r] & (r != cols)) and not np.any(held[cols] & (r != cols))
    for obj in (ksp, plain):
        obj.destroy()


def test_a_value_outside_the_structure_grows_it():
    """A multiplier-multiplier coupling no law writes today (an elastic interface could): it is
    found at the next set-up, the structure grows, and the step is that of the changed J."""
    P, PETSc, F = hex7_problem(loaded=True, matrix="sbaij")
    from ancf_petsc.linalg.compact_factor import multiplier_mask
    ksp, ctx = _compact(PETSc, P)
    x = F.duplicate()
    ksp.solve(F, x)
    assert ctx.analyses == 1
    m = np.flatnonzero(multiplier_mask(P) & ~P.fixed_mask)
    i, j = int(m[0]), int(m[1])                 # two multipliers of one node (a stored block)
    assert i // 18 == j // 18
    P.J.setValue(i, j, 1e-3 * abs(P.J.getValue(i, i)) + 1.0)
    P.J.assemble()
    ksp.setOperators(P.J, P.J)
    ksp.solve(F, x)
    assert ctx.analyses == 2 and i * P.J.getSize()[0] + j in ctx.kept
    y = F.duplicate()
    plain = _mumps(PETSc, P.J)
    plain.solve(F, y)
    # the step of the changed J, to rounding, which differs between CPUs (OpenBLAS picks its
    # kernels by CPU: 5.9e-12 against plain MUMPS's 2.7e-13, |F| = 0.064, on one, 2026-12-02)
    assert _residual(P.J, x, F) <= 10.0 * _residual(P.J, y, F) + 1e-9 * F.norm()
    assert (x - y).norm() <= 1e-7 * y.norm()
    for obj in (ksp, plain):
        obj.destroy()


def test_a_failed_factorisation_fails_the_preconditioner():
    """A singular matrix without null-pivot detection: MUMPS stops (INFOG(1) = −10) and the
    outer KSP says DIVERGED_PCSETUP_FAILED (−11), as with MUMPS as the preconditioner itself (SNES then
    reports DIVERGED_LINEAR_SOLVE and the stepper cuts back)."""
    petsc_init()
    from petsc4py import PETSc
    from ancf_petsc.linalg.compact_factor import install
    J = PETSc.Mat().createSBAIJ(4, 2, nnz=2, comm=PETSc.COMM_SELF)
    J.setOption(PETSc.Mat.Option.IGNORE_LOWER_TRIANGULAR, True)
    J.setValuesBlocked([0], [0], np.array([[2.0, 1.0], [1.0, 2.0]]))
    J.setValuesBlocked([0], [1], np.zeros((2, 2)))
    J.setValuesBlocked([1], [1], np.zeros((2, 2)))
    J.assemble()
    ksp = PETSc.KSP().create(comm=PETSc.COMM_SELF)
    ksp.setType("preonly")
    ksp.setOperators(J, J)
    opts = PETSc.Options()
    opts["mat_mumps_icntl_24"] = "0"
    try:
        ctx = install(ksp, np.zeros(4, bool), np.array([False, False, True, True]))
        b = J.createVecLeft()
        b.set(1.0)
        x = b.duplicate()
        ksp.solve(b, x)
        assert ksp.getConvergedReason() == PETSc.KSP.ConvergedReason.DIVERGED_PCSETUP_FAILED
        assert int(ctx.factor().getMumpsInfog(1)) == -10
    finally:
        opts["mat_mumps_icntl_24"] = "1"
        ksp.destroy()
        J.destroy()


def _both_ways(raw: dict, tmp_path) -> tuple[dict, dict]:
    """The config ``raw`` solved with the compact factor and with every stored entry: their
    summaries, after checking the same Newton iterations and probes within 1e-10."""
    out = {}
    for compact in (True, False):
        raw["solver"] = {"compact_factor": compact}
        raw["output"] = {"dir": str(tmp_path / f"out_{compact}"), "vtk": False}
        cfg = write_config(raw, tmp_path / f"c_{compact}.yaml")
        assert solve_cli(cfg).returncode == 0
        out[compact] = read_summary(tmp_path / f"out_{compact}")
    a, b = out[True], out[False]
    assert a["newton_iterations"] == b["newton_iterations"]
    for sa, sb in zip(a["steps"], b["steps"]):
        for name, pa in sa["probes"].items():
            d = np.asarray(pa["displacement"]) - np.asarray(sb["probes"][name]["displacement"])
            assert np.abs(d).max() <= 1e-10 * np.abs(pa["displacement"]).max()
    return a, b


@pytest.mark.parametrize("mode", ["sliding", "unilateral"])
def test_the_paper_column_is_the_same_with_every_stored_entry(tmp_path, mode):
    """ψ = 45° to 100 N: the compact factorisation (the default on one rank) and MUMPS on
    every stored entry (``solver.compact_factor: false``) take the same Newton iterations and
    agree to rounding; the header names the factorisation."""
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = f"{CONFIGS}/{b['section']['file']}"
    raw["steps"] = [10.0, 100.0]
    raw["contact"]["mode"] = mode
    a, b = _both_ways(raw, tmp_path)
    assert "structural nonzeros" in a["solver"] and "structural nonzeros" not in b["solver"]


def test_the_complementarity_predictor_factors_its_k_compactly_with_the_same_prediction():
    """The unilateral law's Josephy–Newton predictor (petsc/complementarity.py) factors its K
    (the multiplier rows made diagonal) on K's nonzeros too: the same predicted state and status
    as with MUMPS on every stored entry, from rest on the paper's tendon at 10 N."""
    from helpers import build_problem
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = f"{CONFIGS}/{b['section']['file']}"
        b["elements"] = 2
    raw["contact"]["mode"] = "unilateral"
    raw["output"] = {"dir": "unused", "vtk": False}
    out = {}
    for compact in (True, False):
        P, PETSc = build_problem(raw, "sbaij")
        from ancf_petsc.petsc.complementarity import ComplementarityPredictor
        pred = ComplementarityPredictor(P, None, compact=compact)
        assert (pred.ksp.getPC().getType() == "python") == compact
        P.load_factor = 10.0
        X = P.q0.copy()
        P.impose(X)
        assert pred.predict(X)
        out[compact] = (X.getArray().copy(), P.contact.status.copy())
        pred.destroy()
    (xa, sa), (xb, sb) = out[True], out[False]
    assert np.array_equal(sa, sb) and sa.any()
    assert np.abs(xa - xb).max() <= 1e-8 * np.abs(xb).max()


def _soft_column(tmp_path, monkeypatch, budget: int, held: bool = False) -> tuple[dict, list]:
    """The published solver_default set (matrix μ 15 kPa, stiff fibres), twist 0°, uniform bias,
    its own unilateral contact, to 3 kN within ``budget`` Newton iterations; the summary and the
    compact factors' contexts.  Unless ``held``, the complementarity predictor's step is not held
    to the fibres' exponent growth (as before 2026-12-04): its whole linear step from rest sends
    the first solve to |F| ~ 1e26 N, the Jacobian's values grow by orders of magnitude within the
    first level, and the analysis's scaling goes stale (the case the guard is for)."""
    from ancf_petsc.linalg import compact_factor
    from ancf_petsc.petsc import complementarity
    from ancf_petsc.petsc.step_limits import MAX_EXPONENT_GROWTH
    monkeypatch.setattr(complementarity, "MAX_EXPONENT_GROWTH",
                        MAX_EXPONENT_GROWTH if held else float("inf"))
    from ancf_petsc.workflows.envelope import GOH, EnvelopeCell, cell_config
    from helpers import run_inline
    contexts = []
    init = compact_factor.CompactFactor.__init__

    def recorded(self, *args, **kwargs):
        init(self, *args, **kwargs)
        contexts.append(self)
    monkeypatch.setattr(compact_factor.CompactFactor, "__init__", recorded)
    base = [g for g in GOH if g.endswith("_solver_default.yaml")][0]
    raw = cell_config(EnvelopeCell(base, 0.0, "uniform", None, 0.0, 4))
    raw.setdefault("solver", {})["max_newton_iterations"] = budget
    return run_inline(raw, tmp_path / "run"), contexts


def test_a_soft_matrix_column_keeps_accurate_factors_as_its_fibres_stiffen(tmp_path, monkeypatch):
    """The soft column to 3 kN: the Jacobian's values grow by orders of magnitude from the
    analysis at rest to the loaded fibres, and the scaling the analysis's matching gave (ICNTL(6)
    = 5) goes stale.  The guard (``GUARD``) finds solves with residuals 0.3–1.0 of the right-hand
    side and analyses again: 87 Newton iterations, as with a scaling per factorisation (ICNTL(6)
    = 3).  Without the guard (5edf9cb to 2026-12-03) the first level's Newton steps reached
    |F| 1e26 N and every cut-back stalled (next test).  With the predictor's step held (the
    default since 2026-12-04) the column never leaves the analysis's range: 45 iterations, no
    analysis again."""
    from ancf_petsc.linalg.compact_factor import ORDERING
    assert ORDERING[6] == 5
    s, contexts = _soft_column(tmp_path, monkeypatch, 400)
    assert s["status"] == "completed", s["message"]
    assert s["newton_iterations"] <= 100, s["newton_iterations"]
    assert s["factor_reanalyses"] >= 1
    assert s["factor_reanalyses"] == sum(c.reanalyses for c in contexts if c.prefix != "ancf_lcp_")
    held, _ = _soft_column(tmp_path / "held", monkeypatch, 400, held=True)
    assert held["status"] == "completed", held["message"]
    assert held["newton_iterations"] <= 60 and held["factor_reanalyses"] == 0, held


def test_without_the_guard_the_soft_column_stalls_on_stale_scaling(tmp_path, monkeypatch):
    """The guard switched off (a residual bound no solve exceeds): the same column spends a
    budget of 120 Newton iterations without reaching 3 kN (it failed at 0.27 N with 400)."""
    from ancf_petsc.linalg import compact_factor
    monkeypatch.setattr(compact_factor, "GUARD", np.inf)
    s, contexts = _soft_column(tmp_path, monkeypatch, 120)
    assert s["status"] != "completed"
    assert s["factor_reanalyses"] == 0 and sum(c.reanalyses for c in contexts) == 0


def test_the_guard_analyses_again_only_factors_of_an_earlier_analysis(monkeypatch):
    """With a guard no solve passes (GUARD < 0): the first solve's factors are its own
    analysis's and stand; a later set-up's are checked, analysed again once, and the solve
    repeated on the new factors gives the step of plain MUMPS; a factor read for its inertia
    before any solve is checked too."""
    P, PETSc, F = hex7_problem(loaded=True, matrix="sbaij")
    from ancf_petsc.linalg import compact_factor
    monkeypatch.setattr(compact_factor, "GUARD", -1.0)
    ksp, ctx = _compact(PETSc, P)
    x = F.duplicate()
    ksp.solve(F, x)
    assert (ctx.analyses, ctx.reanalyses) == (1, 0)
    P.J.scale(3.0)                                  # new values, the same structure
    ksp.setOperators(P.J, P.J)
    ksp.solve(F, x)
    assert (ctx.analyses, ctx.reanalyses) == (2, 1) and ksp.getConvergedReason() > 0
    plain = _mumps(PETSc, P.J)
    y = F.duplicate()
    plain.solve(F, y)
    assert (x - y).norm() <= 1e-7 * y.norm()
    P.J.scale(0.5)
    ksp.setOperators(P.J, P.J)
    ksp.setUp()
    assert ctx.factor() is not None and (ctx.analyses, ctx.reanalyses) == (3, 2)
    for obj in (ksp, plain):
        obj.destroy()


def test_stored_entries_of_an_aij_matrix_and_its_read_view_keep_its_state():
    """Entry i of a sequential AIJ value array is J[rows[i], cols[i]] (CSR order, not
    inode-compressed); reading it (``read=True``) leaves J's state, so a solver whose operator J
    is does not factor again (an unsymmetric Jacobian was factored twice a set-up without it)."""
    petsc_init()
    from petsc4py import PETSc
    from ancf_petsc.linalg.compact_factor import ValueArray, stored_entries
    rng = np.random.default_rng(4)
    n = 12
    A = rng.standard_normal((n, n)) * (rng.random((n, n)) < 0.4) + np.eye(n)
    J = PETSc.Mat().createAIJ(n, nnz=n, comm=PETSc.COMM_SELF)
    J.setBlockSize(3)
    for i, j in zip(*np.nonzero(A)):
        J.setValue(int(i), int(j), A[i, j])
    J.assemble()
    rows, cols = stored_entries(J)
    assert len(rows) == np.count_nonzero(A)
    state = J.stateGet()
    with ValueArray(J, len(rows), read=True) as a:
        assert np.array_equal(a, A[rows, cols])
    assert J.stateGet() == state
    with ValueArray(J, len(rows)) as a:
        a[0] = a[0]
    assert J.stateGet() > state
    J.destroy()


def test_the_compact_lu_gives_the_newton_step_of_mumps_lu():
    """An AIJ Jacobian (unsymmetric laws: friction, pointwise fade forces) under MUMPS LU: the
    compact factor is LU of its structural nonzeros, both triangles, and gives the step of LU on
    every stored entry; it counts no inertia (LU's pivots are not J's eigenvalues), and a set-up
    leaves J's state (one factorisation)."""
    P, PETSc, F = hex7_problem(loaded=True, matrix="aij")
    from ancf_petsc.linalg.compact_factor import install, multiplier_mask
    from ancf_petsc.linalg.inertia import pivot_counts

    def lu(compact):
        ksp = PETSc.KSP().create(comm=PETSc.COMM_SELF)
        ksp.setOperators(P.J, P.J)
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        ksp.getPC().setFactorSolverType("mumps")
        return ksp, install(ksp, P.fixed_mask, multiplier_mask(P)) if compact else None
    (plain, _), (ksp, ctx) = lu(False), lu(True)
    x0, x1 = F.duplicate(), F.duplicate()
    plain.solve(F, x0)
    state = P.J.stateGet()
    ksp.solve(F, x1)
    assert ksp.getConvergedReason() > 0 and P.J.stateGet() == state
    assert not ctx.symmetric and ctx.C.getType() == "seqaij"
    s = ctx.structure
    assert len(s.dropped) > 0 and len(s.src) + len(s.dropped) == s.size
    assert ctx.ksp.getPC().getType() == "lu"
    assert _backward_error(PETSc, P.J, x1, F) <= 4.0 * np.finfo(float).eps
    assert (x1 - x0).norm() <= 1e-7 * x0.norm()
    assert pivot_counts(ksp) is None
    # ordered by QAMD (ORDERING_LU: half METIS's flops on friction Jacobians), the option put
    # into the database for the analysis only
    factor = ctx.ksp.getPC().getFactorMatrix()
    assert factor.getMumpsIcntl(7) == 6 and factor.getMumpsInfog(7) == 6
    assert not PETSc.Options().hasName("mat_mumps_icntl_7")
    for obj in (ksp, plain):
        obj.destroy()


def test_the_solve_options_choose_the_compact_lus_ordering():
    """``-mat_mumps_icntl_7`` of the solve reaches the compact LU (AMD here), and stays set."""
    P, PETSc, F = hex7_problem(loaded=True, matrix="aij")
    from ancf_petsc.linalg.compact_factor import install, multiplier_mask
    opts = PETSc.Options()
    opts["mat_mumps_icntl_7"] = 0
    try:
        ksp = PETSc.KSP().create(comm=PETSc.COMM_SELF)
        ksp.setOperators(P.J, P.J)
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        ksp.getPC().setFactorSolverType("mumps")
        ctx = install(ksp, P.fixed_mask, multiplier_mask(P))
        x = F.duplicate()
        ksp.solve(F, x)
        assert ksp.getConvergedReason() > 0
        assert ctx.ksp.getPC().getFactorMatrix().getMumpsInfog(7) == 0
        assert opts.getString("mat_mumps_icntl_7", None) == "0"
        ksp.destroy()
    finally:
        opts.delValue("mat_mumps_icntl_7")


def test_a_friction_column_is_the_same_with_every_stored_entry(tmp_path):
    """ψ = 45°, Coulomb μ = 0.3 to 100 N (an unsymmetric Jacobian, AIJ and LU): the compact LU
    and MUMPS LU on every stored entry take the same Newton iterations and agree to rounding;
    the header names the factorisation.  Levels 1 … 100 N: with 10 N from rest in one increment
    Newton hops 50 iterations among stick patterns and rounding picks one of several frictional
    equilibria (docs/gait.md, Limits, "Friction from rest in one large increment")."""
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = f"{CONFIGS}/{b['section']['file']}"
    raw["steps"] = [1.0, 2.5, 5.0, 10.0, 25.0, 50.0, 100.0]
    raw["contact"] = {"mode": "sliding", "tangential": {"law": "coulomb", "friction": 0.3}}
    a, b = _both_ways(raw, tmp_path)
    assert "PC lu (mumps, of the Jacobian's structural nonzeros)" in a["solver"]
    assert "structural nonzeros" not in b["solver"]
