"""Interface shear (issue 27): the elastic interface matrix against the closed-form shear-lag
solution and its two limits, Coulomb friction against mu N and its hysteresis, consistent
tangents (finite differences), and the config keys."""
import numpy as np
import pytest

from helpers import CONFIGS, build_problem, jacobian_and_difference, load_raw, run_inline
from ancf_petsc.contact import hold_bounds
from ancf_petsc.io.reader import read_contact
from ancf_petsc.physics.reference_solutions import shear_lag_transfer

E, B, T, L, F = 1.0e6, 2e-3, 2e-3, 0.05, 5e-4          # configs/shear_lag_sandwich.yaml
EA = E * B * T


def sandwich(k_t: float | None) -> dict:
    raw = load_raw("shear_lag_sandwich.yaml")
    if k_t is None:
        del raw["contact"]["tangential"]
    else:
        raw["contact"]["tangential"]["stiffness"] = k_t
    return raw


def outer_force(out_dir, x: np.ndarray) -> np.ndarray:
    """Axial force the top strip has taken up beyond each x: Σ ω σ_x over its interface
    points past x (ω = reference area × weight; σ is the first beam's traction on the second,
    here the core's on the top strip)."""
    c = read_contact(f"{out_dir}/results.h5", 1)
    top = c["interface"] == 1                     # upper_interface (core|top)
    omega = (c["area"] * c["weight"])[top]
    fx = omega * c["shear_stress"][top, 0]
    x0 = c["x0"][top, 0]
    return np.array([fx[x0 > xe].sum() for xe in x])


@pytest.mark.parametrize("k_t", [1.0e6, 1.0e7])
def test_sandwich_follows_the_shear_lag_solution(k_t, tmp_path):
    """The force the outer bar takes up along the bar, at every element boundary, within 1 % of
    the closed form (shear-lag lengths 26 and 8.2 mm on 3.1 mm elements, L = 50 mm)."""
    s = run_inline(sandwich(k_t), tmp_path)
    assert s["status"] == "completed"
    x = np.linspace(0.0, L, 17)[:-1]
    exact = shear_lag_transfer(x, L, EA, EA, k_t * B, F)
    beam = outer_force(tmp_path, x)
    err = np.abs(beam - exact).max() / exact[0]
    assert err < 0.01, (err, beam, exact)
    # the support of the outer strip carries what the interface passed on
    root = -s["steps"][-1]["reactions"]["top.0"][0]
    assert abs(root - exact[0]) < 0.01 * exact[0]


def test_sandwich_limits_are_sliding_and_bonded(tmp_path):
    """k_t → 0 gives frictionless sliding, k_t → ∞ the bonded load share EA_o/(EA_c + 2 EA_o)
    at the outer strip's root, each within 0.1 %."""
    sliding = run_inline(sandwich(None), tmp_path / "sliding")
    soft = run_inline(sandwich(1e-2), tmp_path / "soft")
    u0 = sliding["steps"][-1]["probes"]["core"]["displacement"][0]
    assert abs(soft["steps"][-1]["probes"]["core"]["displacement"][0] - u0) < 1e-3 * abs(u0)
    # shear-lag length 2.6 mm; the stiff layer leaves a residual floor near 1e-9 N with these
    # 5e-4 N loads (well above the default 1e-10 of the load): absolute tolerance 1e-12 N·20
    bonded = run_inline(sandwich(1e8), tmp_path / "bonded", petsc={"snes_atol": "2e-11"})
    share = -bonded["steps"][-1]["reactions"]["top.0"][0]
    assert abs(share - F / 3.0) < 1e-3 * F / 3.0, share


def _grip_forces(summary) -> np.ndarray:
    return np.array([st["reactions"]["grip"][0] for st in summary["steps"]])


#: the strips' augmentation c (configs/friction_pressed_strips.yaml) and two decades below it
AUGMENTATIONS = (0.1, 0.01, 0.001)


@pytest.fixture(scope="module")
def pressed(tmp_path_factory):
    """configs/friction_pressed_strips.yaml with its augmentation c and c/10, c/100."""
    out = {}
    for c in AUGMENTATIONS:
        raw = load_raw("friction_pressed_strips.yaml")
        assert raw["contact"]["tangential"]["augmentation"] == AUGMENTATIONS[0]
        raw["contact"]["tangential"]["augmentation"] = c
        out[c] = run_inline(raw, tmp_path_factory.mktemp(f"pressed{c:g}"))
        assert out[c]["status"] == "completed", out[c].get("message")
    return out


def test_friction_slides_at_mu_n_and_shows_the_hysteresis(pressed):
    """Sliding carries mu N (exact: every point slides with p > 0), sticking less; on every
    reversal of the pull the force goes through the stick range to the other sign."""
    muN = 0.5 * 0.01
    steps = pressed[AUGMENTATIONS[0]]["steps"]
    lam = np.array([st["load_factor"] for st in steps])
    R = _grip_forces(pressed[AUGMENTATIONS[0]])
    sliding_out = (lam >= 1.25) & (lam <= 2.0)
    sliding_back = (lam >= 2.25) & (lam <= 3.0)
    assert np.allclose(R[sliding_out], muN, rtol=1e-4) and np.allclose(R[sliding_back], -muN, rtol=1e-4)
    assert np.all(np.abs(R) <= muN * (1 + 1e-4))
    assert 0.0 < R[lam == 1.05][0] < muN                      # sticking at the start of the pull
    # the loop: the same pull displacement carries opposite forces going out and coming back
    u = np.array([st["probes"]["grip"]["displacement"][0] for st in steps])
    out = lam == 1.5
    back = np.isclose(lam, 2.25)
    assert np.isclose(u[out][0], u[back][0], atol=1e-9) and R[out][0] > 0 > R[back][0]


def test_friction_answers_do_not_depend_on_the_augmentation(pressed):
    """Stick is exact (tangential multipliers): two decades of the augmentation c, which only
    steers Newton's iteration, give the same grip force at every level, sticking or sliding,
    to 0.1 % of mu N (measured: 4e-9), each level reached without a cut-back."""
    muN = 0.5 * 0.01
    R = {c: _grip_forces(pressed[c]) for c in AUGMENTATIONS}
    for c in AUGMENTATIONS[1:]:
        assert np.abs(R[c] - R[AUGMENTATIONS[0]]).max() < 1e-3 * muN, c
    for c in AUGMENTATIONS:
        assert sum(st["cutbacks"] for st in pressed[c]["steps"]) == 0, c


@pytest.mark.slow
def test_a_friction_failure_names_the_augmentation(tmp_path):
    """c = 1e3 on the pressed strips cycles at the first reversal (c = 0.1 passes): the message
    names contact.tangential.augmentation and its value, not only the increment and mu (21 s)."""
    raw = load_raw("friction_pressed_strips.yaml")
    raw["contact"]["tangential"]["augmentation"] = 1e3
    raw["steps"] = [1, 2, 2.05]
    s = run_inline(raw, tmp_path)
    assert s["status"] == "failed" and "tangential functions flip" in s["message"], s["message"]
    assert "a smaller contact.tangential.augmentation (c = 1000 here" in s["message"], s["message"]


def _achilles(tangential, elements=2, mode="sliding", fix=None):
    raw = load_raw("achilles_type3_psi45.yaml")
    for bc in raw["boundary_conditions"] if fix else ():
        bc["fix"] = fix           # clamped: the supported ends' pressure functions are folded
    for b in raw["beams"]:
        b["elements"] = elements
    raw["contact"] = {"mode": mode, "tangential": tangential}
    return raw


def _state(P, seed, history):
    """A deformed state with multipliers and, for friction, an increment begun nearby (anchor)
    and tangential multipliers of half or twice their bound: some functions stick, others slide."""
    rng = np.random.default_rng(seed)
    P.load_factor = 50.0
    X = P.q0.copy()
    free = ~P.fixed_mask
    q = X.getArray().reshape(-1, 6, 3)
    noise = rng.standard_normal(q.shape)
    noise[:, 1:3] *= 20.0
    noise[:, 3:] *= 200.0
    noise[~P.owned_physical] = 5.0 * rng.standard_normal(q[~P.owned_physical].shape)
    X.setArray(X.getArray() + 2e-6 * noise.ravel() * free)
    if history:
        c = P.contact
        term = c.terms[0]
        st = c.evaluate(P.exchange.local_state(X).copy(), P.exchange.needed)
        ev = st.terms["shear"]
        # the increment started 0.1 µm of tangential slip away
        n = st.pr.n
        s = rng.standard_normal(ev.d.shape)
        s -= np.einsum("pi,pi->p", s, n)[:, None] * n
        term.state["anchor"][c.local] = ev.d - 1e-7 * s / np.linalg.norm(s, axis=1)[:, None]
        # y in the tangent plane of n̄ with |y| half or twice the bound μ ẑ
        u = rng.standard_normal(ev.y.shape)
        u -= np.einsum("ki,ki->k", u, ev.nbar)[:, None] * ev.nbar
        size = ev.bound * rng.choice([0.5, 2.0], len(ev.y))
        y = size[:, None] * u / np.linalg.norm(u, axis=1)[:, None]
        X.getArray()[term.tdof[c.mults].ravel()] = y.ravel()           # serial: global = local
        c._cache = None
    return X, free


def test_the_default_augmentation_is_the_shear_over_young_ratio():
    """Coulomb's c defaults to G/E = (3K + μ) / 9K of the beam that sets k_s = E h (the softest
    E h: a tangential traction meets G h); a given ``augmentation`` wins."""
    from ancf_petsc.contact.multipliers import reference_modulus, reference_size
    P, _ = build_problem(_achilles({"law": "coulomb", "friction": 0.3}))
    beams = [b for itf in P.contact.interfaces for b in (itf.a, itf.b)]
    soft = min(beams, key=lambda b: reference_modulus(b) * reference_size(b))
    K, mu = soft.material.K, soft.material.mu
    assert len({b.material.mu for b in beams}) > 1              # the beams differ: the choice matters
    assert P.contact.terms[0].augmentation == pytest.approx((3 * K + mu) / (9 * K), rel=1e-12)
    assert 1 / 3 < P.contact.terms[0].augmentation < 0.36
    P, _ = build_problem(_achilles({"law": "coulomb", "friction": 0.3, "augmentation": 2.0}))
    assert P.contact.terms[0].augmentation == 2.0


@pytest.mark.parametrize("tangential, history", [
    ({"law": "elastic", "stiffness": 1e10}, False),
    ({"law": "coulomb", "friction": 0.3}, False),
    ({"law": "coulomb", "friction": 0.3}, True),
    ({"law": "coulomb", "friction": 3.0, "augmentation": 10.0}, True),
    ({"law": "coulomb", "friction": 0.3}, "clamped"),
    ({"law": "coulomb", "friction": 0.3, "supported_ends": "merge"}, True),
    ({"law": "coulomb", "friction": 3.0, "augmentation": 10.0, "supported_ends": "merge"}, True),
    ({"law": "coulomb", "friction": 0.3, "supported_ends": "merge"}, "clamped")])
def test_shear_jacobian_matches_finite_differences(tangential, history):
    """J v against central differences of F at deformed states with pressures of both signs
    (friction: sticking and sliding functions, the normal's rotation and the bounds' coupling
    to the pressures included; also with clamped roots, whose end pressure functions are
    folded, and with the roots' tangential functions folded, ``supported_ends: merge``); the
    elastic matrix's Jacobian is symmetric."""
    P, PETSc = build_problem(_achilles(tangential, fix="clamped" if history == "clamped" else None))
    if tangential.get("supported_ends") == "merge":        # the roots' functions are folded
        assert P.contact.space.tdrop.sum() == 2 * len(P.contact.interfaces)
    X, free = _state(P, 3, history)
    st = P.contact.evaluate(P.exchange.local_state(X).copy(), P.exchange.needed)
    if tangential["law"] == "coulomb" and history:
        ev = st.terms["shear"]
        assert ev.m_stick.sum() > 0 and ev.slide.sum() > 0
    P.jacobian(None, X, P.J, P.J)
    rng = np.random.default_rng(7)
    # a sliding function's direction turns fast: its rows' central differences err as h²
    # (measured 8e-4 / 8e-6 / 2e-7 at h = 1e-6 / 1e-7 / 1e-8), so the finer step there
    h = 1e-8 if history else 1e-7
    for _ in range(3):
        v = X.duplicate()
        v.setArray(rng.standard_normal(X.getLocalSize()) * free * 1e-3)
        jv, fd, _, _ = jacobian_and_difference(P, X, v, h)
        err = np.abs(jv - fd)[free].max() / np.abs(jv).max()
        assert err < 1e-6, err
    if tangential["law"] == "elastic":
        Jd = P.J.convert("dense", PETSc.Mat()).getDenseArray()
        assert np.abs(Jd - Jd.T).max() <= 1e-9 * np.abs(Jd).max()


def test_friction_jacobian_with_the_bounds_held_matches_finite_differences():
    """Tresca's problem (the bounds μ ẑ held at a state's, ``contact.hold_bounds``; the fixed
    point of solving/newton.py): J v against central differences of F with the bounds held, at
    a state where functions stick and slide (folded roots); the bounds' coupling to the
    pressures is gone from J (the pressures' columns of the sliding rows change)."""
    P, PETSc = build_problem(_achilles({"law": "coulomb", "friction": 0.3, "supported_ends": "merge"}))
    X, free = _state(P, 3, True)
    F = P.F.duplicate()
    P.residual(None, X, F)                              # the bounds at X
    P.jacobian(None, X, P.J, P.J)
    coulomb = P.J.convert("dense", PETSc.Mat()).getDenseArray().copy()
    assert hold_bounds(P.contact) == float("inf")       # the first hold
    try:
        st = P.contact.evaluate(P.exchange.local_state(X).copy(), P.exchange.needed)
        ev = st.terms["shear"]
        assert ev.slide.sum() > 0 and ev.m_stick.sum() > 0
        P.jacobian(None, X, P.J, P.J)
        tresca = P.J.convert("dense", PETSc.Mat()).getDenseArray()
        assert np.abs(tresca - coulomb).max() > 1e-3 * np.abs(coulomb).max()
        rng = np.random.default_rng(11)
        for _ in range(3):
            v = X.duplicate()
            v.setArray(rng.standard_normal(X.getLocalSize()) * free * 1e-3)
            jv, fd, _, _ = jacobian_and_difference(P, X, v, 1e-8)
            assert np.abs(jv - fd)[free].max() / np.abs(jv).max() < 1e-6
        P.residual(None, X, F)
        assert hold_bounds(P.contact) == 0.0            # held at the same state: no change
    finally:
        hold_bounds(P.contact, False)


def test_displacement_control_gives_the_state_of_the_force(tmp_path):
    """The paper's tendon (ψ = 45°, 2 elements) pulled to 400 N, and stretched instead by the
    soleus end displacement that force produced: the same state to 1e-8 and the grip's
    reaction is the force."""
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["elements"] = 2
    raw["steps"] = [100.0, 400.0]
    force = run_inline(raw, tmp_path / "force")
    ux = force["steps"][-1]["probes"]["soleus"]["displacement"][0]
    raw["loads"] = []
    raw["boundary_conditions"].append({"beam": "soleus", "node": "last", "name": "grip",
                                       "displacement": {"r": {"x": ux}}})
    raw["steps"] = [0.25, 1.0]
    moved = run_inline(raw, tmp_path / "moved")
    from ancf_petsc.io.reader import read_results
    a = read_results(str(tmp_path / "force")).nodal_vectors(2)
    b = read_results(str(tmp_path / "moved")).nodal_vectors(2)
    assert np.abs(a - b).max() <= 1e-8 * np.abs(a).max()
    assert abs(moved["steps"][-1]["reactions"]["grip"][0] - 400.0) < 1e-8 * 400.0


@pytest.mark.parametrize("contact, key, words", [
    ({"tangential": {"law": "friction"}}, "contact.tangential.law", "elastic"),
    ({"tangential": {"law": "coulomb"}}, "contact.tangential.friction", "missing"),
    ({"tangential": {"law": "coulomb", "friction": -0.1}}, "contact.tangential.friction", "> 0"),
    # YAML's .nan / .inf: a TypeError traceback (the message's '>= {lo:g}' with no lower bound)
    ({"tangential": {"law": "coulomb", "friction": float("nan")}}, "contact.tangential.friction",
     "must be a finite number > 0 and <= 10"),
    ({"tangential": {"law": "elastic", "stiffness": float("inf")}}, "contact.tangential.stiffness",
     "must be a finite number > 0 (k_t"),
    ({"tangential": {"law": "coulomb", "friction": 0.3, "stiffness": 1e6}}, "contact.tangential.stiffness",
     "not a value of law coulomb"),
    ({"tangential": {"law": "elastic"}}, "contact.tangential.stiffness", "thickness"),
    # half of the pair named stiffness as missing, which was given neither
    ({"tangential": {"law": "elastic", "shear_modulus": 1e6}}, "contact.tangential.thickness",
     "missing value (required with shear_modulus)"),
    ({"tangential": {"law": "elastic", "thickness": 1e-5}}, "contact.tangential.shear_modulus",
     "missing value (required with thickness)"),
    ({"tangential": {"law": "elastic", "stiffness": 1e6, "thickness": 3e-5}}, "contact.tangential", "not both"),
    ({"tangential": {"law": "coulomb", "friction": 0.3, "augmentation": 0}}, "contact.tangential.augmentation",
     ">= 0.0001"),
    # c = 1e-9 took 20 698 Newton iterations without a level (2026-12-06)
    ({"tangential": {"law": "coulomb", "friction": 0.3, "augmentation": 1e-9}}, "contact.tangential.augmentation",
     ">= 0.0001"),
    ({"tangential": {"law": "coulomb", "friction": 0.3, "supported_ends": "fold"}},
     "contact.tangential.supported_ends", "merge"),
    ({"tangential": {"law": "elastic", "stiffness": 1e6, "supported_ends": "merge"}},
     "contact.tangential.supported_ends", "not a value of law elastic"),
])
def test_tangential_config_errors_name_the_key(contact, key, words):
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.errors import InputError
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["contact"] = dict(raw["contact"], **contact)
    with pytest.raises(InputError) as info:
        parse_config(raw, base_dir=CONFIGS)
    assert info.value.path == key and words in info.value.message, (info.value.path, info.value.message)


@pytest.mark.parametrize("bc, key, words", [
    ({"beam": "soleus", "node": "last"}, "boundary_conditions[3]", "fix"),
    ({"beam": "soleus", "node": "last", "fix": {"r": "x"}, "displacement": {"r": {"x": 1e-3}}},
     "boundary_conditions[3].displacement.r.x", "also in fix"),
    ({"beam": "soleus", "node": "last", "displacement": {"r": {"w": 1e-3}}},
     "boundary_conditions[3].displacement.r.w", "unknown key"),
    ({"beam": "soleus", "node": "last", "fix": {"r": "y"}, "curve": [[0, 0], [1, 1]]},
     "boundary_conditions[3].curve", "prescribes none"),
    ({"beam": "soleus", "node": "last", "displacement": {"r": {"x": 1e-3}}, "curve": [[0, 0], [0, 1]]},
     "boundary_conditions[3].curve", "increasing"),
    ({"beam": "soleus", "node": "last", "displacement": {"r": {"x": 1e-3}}, "curve": [[0, 0], [100, 1]]},
     "boundary_conditions[3].curve", "extend it"),
])
def test_displacement_config_errors_name_the_key(bc, key, words):
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.errors import InputError
    raw = load_raw("achilles_type3_psi45.yaml")
    raw["boundary_conditions"].append(bc)
    with pytest.raises(InputError) as info:
        parse_config(raw, base_dir=CONFIGS)
    assert info.value.path == key and words in info.value.message, (info.value.path, info.value.message)


def _reaction_table(summary) -> np.ndarray:
    return np.array([[st["reactions"][k] for k in sorted(st["reactions"])] for st in summary["steps"]])


@pytest.mark.mpi
@pytest.mark.slow
@pytest.mark.parametrize("name, levels", [("friction_pressed_strips.yaml", [1, 1.5, 2, 2.1, 2.2, 2.3, 2.4]),
                                          ("shear_lag_sandwich.yaml", None)])
def test_tangential_laws_give_the_serial_answer_on_2_and_3_ranks(tmp_path, name, levels):
    """Friction (its return mapping and history at every point, the pressure of multipliers
    shared by two ranks) and the elastic matrix on 1, 2 and 3 ranks: the same probes and
    reactions at every level, every component (the sandwich's bodies are all clamped at x = 0:
    with the ends' pressure functions kept they repeated the supports and the
    normal reactions differed by 1.5e-3 between rank counts; folded, by 2e-13)."""
    from helpers import assert_same_as_serial, probes_table, run_on_ranks
    raw = load_raw(name)
    if levels:
        raw["steps"] = levels                              # out, then back past the turn
    runs = run_on_ranks(raw, tmp_path, ranks=(1, 2, 3))
    assert_same_as_serial({n: probes_table(s) for n, (_, s) in runs.items()})
    assert_same_as_serial({n: _reaction_table(s) for n, (_, s) in runs.items()})


@pytest.mark.mpi
@pytest.mark.slow
def test_friction_restarts_with_its_history(tmp_path):
    """A run of the pressed strips stopped after the pull reversed, continued by --restart on 2
    ranks: the history of every contact point (its stress and position at the last increment)
    comes back, so the rest of the loop equals the uninterrupted run's."""
    from helpers import probes_table, read_summary, solve_cli, write_config
    raw = load_raw("friction_pressed_strips.yaml")
    raw["output"] = {"dir": str(tmp_path / "full"), "vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "full.yaml"), extra=["--quiet"])
    assert p.returncode == 0, p.stderr
    short = dict(raw, steps=raw["steps"][:25], output={"dir": str(tmp_path / "part"), "vtk": False})
    p = solve_cli(write_config(short, tmp_path / "short.yaml"), extra=["--quiet"])
    assert p.returncode == 0, p.stderr
    raw["output"] = {"dir": str(tmp_path / "part"), "vtk": False}
    p = solve_cli(write_config(raw, tmp_path / "again.yaml"), ranks=2,
                  extra=["--restart", str(tmp_path / "part"), "--quiet"])
    assert p.returncode == 0, p.stdout + p.stderr
    full, part = read_summary(tmp_path / "full"), read_summary(tmp_path / "part")
    assert part["restarted_from"]["step"] == 25 and len(part["steps"]) == len(full["steps"])
    a, b = _reaction_table(full), _reaction_table(part)
    assert np.abs(a - b).max() <= 1e-8 * np.abs(a).max()
    a, b = probes_table(full), probes_table(part)
    assert np.abs(a - b).max() <= 1e-8 * np.abs(a).max()
