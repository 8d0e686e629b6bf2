"""The normal force acting past the ends of the interface curves (summary.json, per level and
interface: ``past_ends_force``, ``past_ends_share``; docs/contact.md, "Contact past the ends of
the interface curves").  A contact point whose partner place lies past the end of the partner's
interface curve (or beam) measures its gap to the continued end piece of the interface surface,
not to the outline, and its weight fades there.  The reported force is checked against the point
fields written to results.h5, recomputed point by point, and on 1, 2 and 3 ranks."""
import h5py
import numpy as np
import pytest

from ancf_petsc.workflows.envelope import NEO, EnvelopeCell, cell_config

from helpers import build_problem, load_raw, run_inline, run_on_ranks

#: the gait envelope's unilateral column at twist 90 deg, uniform bias, to 200 N: points of every
#: interface slide past the ends of their partners' curves (about 60 % of the force)
CELL = EnvelopeCell(NEO, 90, "uniform", "unilateral", levels=(30.0, 100.0, 200.0))


def _recomputed(raw: dict, out_dir) -> dict:
    """Per interface name: Σ|τ_p| over the points of the last level whose partner place
    (results.h5's ``projection``) is off the interface surface (``Projector.on_surface``), and
    over all points; τ_p = pressure × area (docs/running.md, "Contact outputs")."""
    P, _ = build_problem(raw)
    c = P.contact
    with h5py.File(out_dir / "results.h5") as f:
        g = f["steps"][sorted(f["steps"])[-1]]["contact"]
        ids = np.arange(len(g["pressure"]))
        tau = np.abs(g["pressure"][()] * g["area"][()])
        proj, itf = g["projection"][()], g["interface"][()]
    on = c.projector.on_surface(ids, proj[:, 0].astype(np.int64), proj[:, 1], proj[:, 2])
    return {i.name: (tau[(itf == k) & ~on].sum(), tau[itf == k].sum()) for k, i in enumerate(c.interfaces)}


def test_the_force_past_the_ends_is_that_of_the_points_off_the_interface_surface(tmp_path):
    """The 90 deg unilateral column: summary.json's ``past_ends_force`` of every interface equals
    the force of its points off the interface surface recomputed from the written point fields,
    and ``past_ends_share`` that force over the interface's Σ|τ_p| (= pressing − tension force);
    here a large share of it (the contact concentrates where the outlines meet)."""
    raw = cell_config(CELL)
    s = run_inline(raw, tmp_path)
    assert s["status"] == "completed"
    report = s["steps"][-1]["contact"]
    expected = _recomputed(raw, tmp_path)
    for name, (past, total) in expected.items():
        r = report[name]
        assert r["past_ends_force"] == pytest.approx(past, rel=1e-12, abs=1e-15)
        assert r["pressing_force"] - r["tension_force"] == pytest.approx(total, rel=1e-12)
        assert r["past_ends_share"] == pytest.approx(past / total if total else 0.0, rel=1e-12, abs=1e-15)
        assert 0.0 <= r["past_ends_share"] <= 1.0
    past = sum(r["past_ends_force"] for r in report.values())
    total = sum(r["pressing_force"] - r["tension_force"] for r in report.values())
    assert past > 0.3 * total


def test_nothing_acts_past_the_ends_of_an_untwisted_tendon_pulled_evenly(tmp_path):
    """Twist 0, sliding, uniform bias, to 400 N: no point slides off its partner's interface
    surface (measured: zero at every level to 1.2 kN); the paper's ψ = 45° column keeps it small
    (4.5 % of the interfaces' force at 400 N, its last level)."""
    s = run_inline(cell_config(EnvelopeCell(NEO, 0, "uniform", "sliding", levels=(100.0, 400.0))),
                   tmp_path / "untwisted")
    for step in s["steps"]:
        assert all(r["past_ends_force"] == 0.0 == r["past_ends_share"] for r in step["contact"].values())
    paper = run_inline(load_raw("achilles_type3_psi45.yaml"), tmp_path / "paper")["steps"][-1]["contact"]
    past = sum(r["past_ends_force"] for r in paper.values())
    total = sum(r["pressing_force"] - r["tension_force"] for r in paper.values())
    assert 0.0 < past < 0.06 * total


@pytest.mark.mpi
@pytest.mark.slow
def test_the_force_past_the_ends_is_the_serial_one_on_every_rank_count(tmp_path):
    """Each rank sums its own points (the report's columns are summed over the ranks): 2 and 3
    ranks report the serial force past the ends at every level and interface."""
    runs = run_on_ranks(cell_config(CELL), tmp_path)
    serial = runs[1][1]["steps"]
    for n, (_, s) in runs.items():
        assert len(s["steps"]) == len(serial), n
        for step, ref in zip(s["steps"], serial):
            for name, r in ref["contact"].items():
                got = step["contact"][name]
                scale = max(ref_r["pressing_force"] - ref_r["tension_force"] for ref_r in ref["contact"].values())
                assert abs(got["past_ends_force"] - r["past_ends_force"]) <= 1e-9 * scale, (n, step["load_factor"], name)


def _beam_balance(raw: dict, out_dir) -> tuple[dict, np.ndarray]:
    """At the last level written to results.h5: per interface Σ_p τ_p (the contact points' forces
    along their normals, τ_p with its fade weight, from the contact evaluated at the written state)
    and per beam the across components (y, z: the end loads pull along x) of its support reaction
    plus the contact forces it receives, Σ ±τ_p n_p: zero where the τ_p are the forces acting."""
    P, _ = build_problem(raw)
    c = P.contact
    beams = [b.name for b in P.model.beams]
    with h5py.File(out_dir / "results.h5") as f:
        g = f["steps"][sorted(f["steps"])[-1]]
        c.restore_state(g["contact/projection"][()], g["contact/multiplier_active"][()])
        X = P.global_vector(g["restart/blocks"][()].ravel())
        balance = g["reactions"][()][:, 1:].copy()
    c.allow_update = False
    st = c.evaluate(P.exchange.local_state(X).copy(), P.exchange.needed)
    forces = {}
    for k, itf in enumerate(c.interfaces):
        on = c.points.itf[c.local] == k
        f = st.tau[on] @ st.pr.n[on]                     # on A (the points' beam), −f on B
        balance[beams.index(itf.a.name)] += f[1:]
        balance[beams.index(itf.b.name)] -= f[1:]
        forces[itf.name] = float(st.tau[on].sum())
    return forces, balance


def test_the_normal_force_is_what_acts_on_the_beams_where_points_fade(tmp_path):
    """normal_force was Σ_k λ_k A_k, the functions' coefficients times their whole areas, while the
    forces acting are the points' τ_p, whose weights fade past the ends: twist 0, sliding,
    gastrocnemius-biased, at 3 kN it read −87.35 N on mg_sol against pressing + tension = −111.52 N
    (the walking stride, frame 51: 392.5 against −87.9 N, λ_k up to 72 MPa on a function a third
    of whose area still counts).  The τ_p balance each beam's support reaction (to 0.01 N here;
    Σ λ_k φ_k without the weights leaves 24 N); normal_force is now their sum, = pressing_force +
    tension_force, on every level and interface."""
    raw = cell_config(EnvelopeCell(NEO, 0, "gastrocnemius", "sliding", levels=(1200.0, 2000.0, 3000.0)))
    s = run_inline(raw, tmp_path)
    assert s["status"] == "completed"
    for step in s["steps"]:
        for name, r in step["contact"].items():
            both = r["pressing_force"] - r["tension_force"]
            assert r["normal_force"] == pytest.approx(r["pressing_force"] + r["tension_force"],
                                                      rel=1e-12, abs=1e-12 * both), (step["load_factor"], name)
    report = s["steps"][-1]["contact"]
    assert report["mg_sol (soleus|medial_gastrocnemius)"]["past_ends_force"] > 1.0     # points fade here
    forces, balance = _beam_balance(raw, tmp_path)
    assert np.abs(balance).max() < 0.01
    for name, force in forces.items():
        assert report[name]["normal_force"] == pytest.approx(force, rel=1e-9, abs=1e-9)
