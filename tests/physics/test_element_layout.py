"""The element layout as data (physics/elements, issue 42): the registry's monomials are the
section field 3363 and 3333 always had (bitwise), and an element registered in the test itself
runs everything a run does — model, supports, probes, contact, results.h5, VTU, restart — with a
node block of its own: a copy of 3363, a complete cubic section field (10 vectors, 30 DOFs per
node) and 3363's section on four axial nodes."""
import copy
import os
import subprocess
import sys

import h5py
import numpy as np
import pytest

from ancf_petsc.config.values import ConfigError
from ancf_petsc.contact.surface import shape_on_curve, shape_third_on_curve
from ancf_petsc.physics.elements import ELEMENTS, Element, NodeBlock, complete_monomials, register
from helpers import (CONFIGS, MPI_ENV, ROOT, assert_jacobian_and_gradient, build_problem, load_raw,
                     perturbed_state, petsc_init, probes_table, read_summary, two_beam_twisted, write_config)

BLOCK = ELEMENTS["3363"].block


# ------------------------------------------------------------------ 3363 and 3333 as they were
def _literal_monomials(y, z):
    """The section field of element3363 before issue 42, written out (m, m_y, m_z)."""
    one, zero = np.ones_like(y), np.zeros_like(y)
    return (np.stack([one, y, z, 0.5 * y * y, 0.5 * z * z, y * z], axis=-1),
            np.stack([zero, one, zero, y, zero, z], axis=-1),
            np.stack([zero, zero, one, zero, z, y], axis=-1))


def _literal_lagrange(xi):
    L = np.stack([0.5 * xi * (xi - 1.0), 1.0 - xi * xi, 0.5 * xi * (xi + 1.0)], axis=-1)
    return L, np.stack([xi - 0.5, -2.0 * xi, xi + 0.5], axis=-1)


def _points(n=500, seed=11):
    rng = np.random.default_rng(seed)
    return rng.uniform(-1, 1, n), rng.uniform(-0.01, 0.01, n), rng.uniform(-0.02, 0.02, n)


def test_registry_monomials_are_3363s_and_3333s_section_field_bitwise():
    xi, y, z = _points()
    for e, cols in ((ELEMENTS["3363"], slice(None)), (ELEMENTS["3333"], slice(0, 3))):
        for new, old in zip(e.section_monomials(y, z), _literal_monomials(y, z)):
            assert np.array_equal(new, old)
        L, dL = _literal_lagrange(xi)
        m, my, mz = (a[:, cols] for a in _literal_monomials(y, z))
        N, dN = e.shape_functions(xi, y, z)
        n = len(xi)
        assert np.array_equal(N, (L[:, :, None] * m[:, None, :]).reshape(n, -1))
        assert np.array_equal(dN[:, :, 0], (dL[:, :, None] * m[:, None, :]).reshape(n, -1))
        assert np.array_equal(dN[:, :, 1], (L[:, :, None] * my[:, None, :]).reshape(n, -1))
        assert np.array_equal(dN[:, :, 2], (L[:, :, None] * mz[:, None, :]).reshape(n, -1))
    assert BLOCK.names == ("r", "r_y", "r_z", "r_yy", "r_zz", "r_yz") and BLOCK.dofs_per_node == 18
    assert ELEMENTS["3333"].held == (3, 4, 5) and ELEMENTS["3333"].block is BLOCK


def test_contact_surface_derivatives_are_the_literal_chain_rule_bitwise():
    """shape_on_curve / shape_third_on_curve read the block's monomials; their values are the
    hand-written 3363 formulas they replaced, to the last bit."""
    xi, y, z = _points(300, 5)
    rng = np.random.default_rng(6)
    S = np.column_stack([y, z])
    S1, S2, S3 = (rng.standard_normal((len(xi), 2)) for _ in range(3))
    m, my, mz = _literal_monomials(y, z)
    y1, z1, y2, z2 = S1[:, :1], S1[:, 1:], S2[:, :1], S2[:, 1:]
    mt = my * y1 + mz * z1
    mtt = my * y2 + mz * z2
    mtt[:, 3:4] += y1 ** 2
    mtt[:, 4:5] += z1 ** 2
    mtt[:, 5:6] += 2.0 * y1 * z1
    mttt = my * S3[:, :1] + mz * S3[:, 1:]
    mttt[:, 3:4] += 3.0 * y1 * y2
    mttt[:, 4:5] += 3.0 * z1 * z2
    mttt[:, 5:6] += 3.0 * (y1 * z2 + y2 * z1)
    L, dL = _literal_lagrange(xi)
    P = len(xi)

    def outer(a, b):
        return (a[:, :, None] * b[:, None, :]).reshape(P, 18)
    N, Nz, Nzz = shape_on_curve(xi, S, S1, S2, BLOCK)
    assert np.array_equal(N, outer(L, m))
    assert np.array_equal(Nz, np.stack([outer(dL, m), outer(L, mt)], -1))
    assert np.array_equal(Nzz[:, :, 1, 1], outer(L, mtt)) and np.array_equal(Nzz[:, :, 0, 1], outer(dL, mt))
    _, Nzzz = shape_third_on_curve(xi, S, S1, S2, S3, BLOCK)
    assert np.array_equal(Nzzz[:, :, 1, 1, 1], outer(L, mttt))
    assert np.array_equal(Nzzz[:, :, 0, 1, 1], outer(dL, mtt))


# ------------------------------------------------------------------ elements registered here
NODES4 = np.array([-1.0, -1.0 / 3.0, 1.0 / 3.0, 1.0])


def _lagrange4(xi):
    """Cubic Lagrange polynomials on four equally spaced nodes and their ξ-derivatives."""
    xi = np.atleast_1d(np.asarray(xi, dtype=float))
    L, dL = np.ones((len(xi), 4)), np.zeros((len(xi), 4))
    for a in range(4):
        others = [b for b in range(4) if b != a]
        den = np.prod([NODES4[a] - NODES4[b] for b in others])
        L[:, a] = np.prod([xi - NODES4[b] for b in others], axis=0) / den
        dL[:, a] = sum(np.prod([xi - NODES4[c] for c in others if c != b], axis=0) for b in others) / den
    return L, dL


def _lagrange4_second(xi):
    xi = np.atleast_1d(np.asarray(xi, dtype=float))
    out = np.zeros((len(xi), 4))
    for a in range(4):
        others = [b for b in range(4) if b != a]
        den = np.prod([NODES4[a] - NODES4[b] for b in others])
        for b in others:
            for c in [c for c in others if c != b]:
                out[:, a] += np.prod([xi - NODES4[d] for d in others if d not in (b, c)], axis=0) / den
    return out


TEST_ELEMENTS = {
    "copy-3363": Element("copy-3363", NodeBlock(BLOCK.monomials)),
    "cubic-section": Element("cubic-section", NodeBlock(complete_monomials(3))),
    "four-node-3363": Element("four-node-3363", NodeBlock(BLOCK.monomials, 4, _lagrange4, _lagrange4_second)),
}


@pytest.fixture
def registered():
    """The test elements in the registry for one test (removed after it)."""
    for e in TEST_ELEMENTS.values():
        register(e)
    yield TEST_ELEMENTS
    for name in TEST_ELEMENTS:
        ELEMENTS.pop(name, None)


def _solve(raw: dict, out, restart=None) -> dict:
    """ancf_petsc.solve of a raw config in this process (the registry is this process's)."""
    petsc_init()
    from ancf_petsc.api import solve
    from ancf_petsc.config.parse import parse_config
    raw = copy.deepcopy(raw)
    raw.setdefault("output", {})["dir"] = str(out)
    res = solve(parse_config(raw, base_dir=CONFIGS), log=lambda *_: None, restart=restart)
    assert res.summary["status"] == "completed", res.summary.get("message")
    return res.summary


def _achilles(element: str, steps: list) -> dict:
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["element"] = element
    raw["steps"] = steps
    raw["probes"] = raw.get("probes", []) + [{"name": "mean", "beam": "soleus", "node": "last", "vector": "mean"}]
    return raw


def _last_state(out) -> np.ndarray:
    with h5py.File(out / "results.h5", "r") as f:
        k = int(f["steps"].attrs["converged"])
        return f[f"steps/step_{k:04d}/nodal_vectors"][()]


def _assert_restart_matches(restarted: np.ndarray, whole: np.ndarray) -> None:
    """As tests/solving/test_restart.py: the uninterrupted answers to 1e-10 of the largest entry
    (the restarted run factors its first matrix afresh: round-off apart)."""
    assert np.abs(restarted - whole).max() <= 1e-10 * np.abs(whole).max()


def _restarted(raw: dict, tmp_path, name: str) -> tuple[np.ndarray, np.ndarray]:
    """The last state of an uninterrupted run of ``raw`` and of a run of its first level
    continued by a restart (``ancf-solve --restart``)."""
    whole, part = tmp_path / f"{name}_whole", tmp_path / f"{name}_part"
    _solve(raw, whole)
    _solve(dict(raw, steps=raw["steps"][:1]), part)
    _solve(raw, part, restart=str(part))
    return _last_state(whole), _last_state(part)


@pytest.mark.slow
def test_a_registered_copy_of_3363_is_3363_through_contact_results_and_restart(registered, tmp_path):
    """The issue's crash (``float(b.element)`` when results were written) is gone: a copy of 3363
    under another name solves the contact column, writes results.h5 (the element name a string in
    the fingerprint) and VTU surfaces, restarts, and its answers are 3363's to the last digit."""
    steps = [10.0, 20.0, 30.0]
    copied = _solve(_achilles("copy-3363", steps), tmp_path / "copy")
    paper = _solve(_achilles("3363", steps), tmp_path / "paper")
    assert np.array_equal(_last_state(tmp_path / "copy"), _last_state(tmp_path / "paper"))
    assert [s["iterations"] for s in copied["steps"]] == [s["iterations"] for s in paper["steps"]]
    assert (tmp_path / "copy" / "surface_0003.vtu").exists()
    with h5py.File(tmp_path / "copy" / "results.h5", "r") as f:
        word = f["model/fingerprint/beams/soleus/element"][()]
        assert bytes(word.astype(np.uint8)).decode() == "copy-3363"
    whole, restarted = _restarted(_achilles("copy-3363", steps), tmp_path, "copy")
    _assert_restart_matches(restarted, whole)


def test_a_cubic_section_field_element_is_exact_in_tension_and_its_tangent_is_the_residuals(registered, tmp_path):
    """10 nodal vectors per node (the complete cubic field, issue 42 item 2's order 3), declared
    in this test only: supports, probes, traction loads, kernels and output read its layout.  One
    element is exact in uniaxial tension (a richer section field contains the uniform
    contraction), and the Jacobian of a pretwisted two-beam model matches central differences."""
    from ancf_petsc.physics.materials import NeoHookean
    from ancf_petsc.physics.reference_solutions import uniaxial_stretches
    cubic = registered["cubic-section"]
    assert cubic.block.dofs_per_node == 30 and cubic.block.names[6:] == ("r_yyy", "r_yyz", "r_yzz", "r_zzz")
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["beams"][0]["element"] = "cubic-section"
    s = _solve(raw, tmp_path / "bar")
    area = next(iter(s["sections"].values()))["area"]
    for step in s["steps"]:
        lam, _ = uniaxial_stretches(NeoHookean(1.0e6, 50.0e6), step["load_factor"] * 45.0 / area)
        assert step["probes"]["tip"]["displacement"][0] == pytest.approx((lam - 1.0) * 0.1, rel=1e-9)
    assert _last_state(tmp_path / "bar").shape[1:] == (10, 3)
    two = two_beam_twisted()
    for b in two["beams"]:
        b["element"] = "cubic-section"
    P, _ = build_problem(two)
    assert P.model.dofs_per_node == 30 and P.blocks[0].rows.shape[1] == 90
    P.load_factor = 0.7
    rng = np.random.default_rng(2)
    X, free = perturbed_state(P, rng, 2e-3)
    P.jacobian(None, X, P.J, P.J)
    assert_jacobian_and_gradient(P, X, free, rng, gradient_rel=1e-5)


@pytest.mark.parametrize("name", ["cubic-section", "four-node-3363"])
def test_an_element_of_another_layout_runs_the_contact_column_and_restarts(registered, tmp_path, name):
    """The Achilles column (sliding contact between three subtendons, the fascicle-free direct
    solver) with a 30-DOF node block, or with four axial nodes per element: contact points,
    projection, multipliers in node blocks of the model's size, results and restart."""
    raw = _achilles(name, [10.0, 20.0])
    if name == "four-node-3363":
        for b in raw["beams"]:
            b["axial_points"] = 4       # two or three points leave the cubic axial field's modes free
    whole, restarted = _restarted(raw, tmp_path, name)
    assert whole.shape[1] == registered[name].block.vectors_per_node
    _assert_restart_matches(restarted, whole)


#: one process per rank registers the cubic element (the registry is a process's) and solves
MPI_SCRIPT = """
import sys
from ancf_petsc.physics.elements import Element, NodeBlock, complete_monomials, register
register(Element("cubic-section", NodeBlock(complete_monomials(3))))
from ancf_petsc import load_config, solve
spec = load_config(sys.argv[1])
spec.output.dir = sys.argv[2]
assert solve(spec, log=lambda line: None).status == "completed"
"""


@pytest.mark.mpi
def test_a_cubic_section_column_on_two_ranks_is_the_serial_one(registered, tmp_path):
    """Results must not depend on the number of ranks: the 30-DOF node blocks cut between ranks
    (layout, ghost exchange, contact multipliers of the other rank's elements)."""
    raw = _achilles("cubic-section", [10.0, 20.0])
    for b in raw["beams"]:
        b["section"]["file"] = f"{CONFIGS}/{b['section']['file']}"
    serial = _solve(raw, tmp_path / "serial")
    cfg = write_config(raw, tmp_path / "cubic.yaml")
    p = subprocess.run(["mpirun", "--oversubscribe", "-n", "2", sys.executable, "-c", MPI_SCRIPT, cfg,
                        str(tmp_path / "two")], capture_output=True, text=True, cwd=ROOT,
                       env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT), timeout=300)
    assert p.returncode == 0, p.stdout + p.stderr
    two = read_summary(tmp_path / "two")
    assert two["ranks"] == 2
    a, b = probes_table(serial), probes_table(two)
    assert np.abs(a - b).max() <= 1e-9 * np.abs(a).max()


def test_beams_of_one_model_share_their_node_block(registered):
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    raw = two_beam_twisted()
    raw["beams"][1]["element"] = "cubic-section"
    with pytest.raises(ConfigError, match=r"beams\[1\]\.element.*node block"):
        build_model(parse_config(raw, base_dir=CONFIGS))
    raw["beams"][1]["element"] = "no-such-element"
    with pytest.raises(ConfigError, match="no-such-element"):
        parse_config(raw, base_dir=CONFIGS)


def test_the_restart_fingerprint_names_the_element_and_reads_older_files():
    """The element is a string in the fingerprint (any registered name); a results.h5 written
    before stores [element number, axial points, locking] and is still the same model."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.io.restart import fingerprint, model_difference
    from ancf_petsc.model.build import build_model
    raw = load_raw("uniaxial_neohookean.yaml")
    now = fingerprint(build_model(parse_config(raw, base_dir=CONFIGS)))
    old = {k: v for k, v in now.items() if k not in ("beams/bar/element", "beams/bar/axial_points_locking")}
    old["beams/bar/element_axial_points_locking"] = np.array([3363.0, 2.0, 0.0])
    assert model_difference(old, now) is None
    raw["beams"][0]["element"] = "3333"
    other = fingerprint(build_model(parse_config(raw, base_dir=CONFIGS)))
    assert model_difference(old, other) == "beams/bar/element (3363 → 3333)"


def test_monomial_derivatives_are_each_monomial_formed_alone_bitwise():
    """``NodeBlock.monomial_derivatives`` (all pairs in one pass) gives, for a quartic block, what
    forming each derivative alone gives: y^p z^q by repeated products, times 1/(p! q!), 0 past
    the exponent; bitwise, at points of both signs and magnitudes from 1e-6 to 1e-2 m."""
    import math
    from ancf_petsc.physics.elements.base import NodeBlock, complete_monomials
    block = NodeBlock(complete_monomials(4))
    rng = np.random.default_rng(3)
    y = rng.standard_normal(50) * 10.0 ** rng.uniform(-6, -2, 50)
    z = rng.standard_normal(50) * 10.0 ** rng.uniform(-6, -2, 50)
    pairs = ((0, 0), (1, 0), (0, 1), (2, 0), (1, 1), (0, 2), (3, 0), (2, 1), (1, 2), (0, 3))

    def power(x, n):
        out = np.ones_like(x) if n == 0 else x
        for _ in range(n - 1):
            out = out * x
        return out

    got = block.monomial_derivatives(y, z, pairs)
    for k, (a, b) in enumerate(pairs):
        for v, (i, j) in enumerate(block.monomials):
            p, q = i - a, j - b
            if p < 0 or q < 0:
                want = np.zeros_like(y)
            else:
                want = (1.0 / (math.factorial(p) * math.factorial(q))) * (power(y, p) * power(z, q))
            assert np.array_equal(got[k, :, v], want), (a, b, i, j)
        assert np.array_equal(block.section_monomials(y, z, a, b), got[k])


def test_too_few_axial_points_for_a_four_node_element_is_a_config_error(registered):
    """An element with four nodes along the beam needs four Gauss points along it (with 2 or 3
    its cubic axial field keeps zero-energy modes): a one-line error naming the key, before any
    model is built; the three-node elements keep their minimum of 2."""
    from ancf_petsc.config.parse import parse_config
    for n in (2, 3):
        raw = _achilles("four-node-3363", [10.0])
        raw["beams"][0]["axial_points"] = n
        with pytest.raises(ConfigError) as err:
            parse_config(raw, base_dir=CONFIGS)
        assert str(err.value).startswith("beams[0].axial_points: must be >= 4 for an element with 4 nodes")
    raw = _achilles("3363", [10.0])
    raw["beams"][0]["axial_points"] = 2
    parse_config(raw, base_dir=CONFIGS)
