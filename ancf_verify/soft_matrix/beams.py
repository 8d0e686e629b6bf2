"""The soft-matrix bar as ANCF beams in-process and their measures."""
from __future__ import annotations

import tempfile

import numpy as np

from ancf_verify.bars.cases import Case, ancf_config
from ancf_verify.fibres.beams import run_ancf
from ancf_verify.fibres.cases import SAMPLE_SCALE
from ancf_verify.paths import CONFIGS
from ancf_verify.soft_matrix.cases import ELEMENTS, LOADS, LOCKINGS, MIDDLE, model_name


def ancf_measures(case: Case, elements: int, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Ē = a0 · C a0 − 1 at the Gauss points (elements, points), the end section's mean displacement
    Σ_k m̄_k Δq_k (m̄_k = ∫ m_k dA / A, the traction's weights) and the span of u_x over the solid's
    end-face sample points (SolidProbe's), state q."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.model.build import build_model
    from ancf_petsc.physics.kernels import deformation_gradient
    model = build_model(parse_config(ancf_config(case, elements, 2, tempfile.mkdtemp()), base_dir=CONFIGS))
    b = model.beams[0]
    local = np.arange(elements)
    G, _, material = model.element_data(b, local)[0]
    F = deformation_gradient(q[b.connectivity[local]][:, :, list(b.vectors)].reshape(len(local), -1, 3), G)
    Fa = np.einsum("...ij,...j->...i", F, material.a0[0])
    m = model.block.section_monomials(b.section.points[:, 0], b.section.points[:, 1])
    mean = b.section.weights @ m / b.section.weights.sum()
    ux = model.block.section_monomials(*(SAMPLE_SCALE * b.section.points).T) @ (q[-1, :, 0] - model.q0[-1, :, 0])
    return np.einsum("...i,...i->...", Fa, Fa) - 1.0, mean @ (q[-1] - model.q0[-1]), float(ux.max() - ux.min())


def run_beam(case: Case, elements: int, tmp: str, model: str, load: str) -> dict:
    """One beam run (verify_solid_fibres.run_ancf) with its load, model name, Ē range over the
    middle half and per element, and the end face's mean displacement."""
    r = run_ancf(case, elements, tmp, model, load)
    E, u_mean, span = ancf_measures(case, elements, r.pop("q"))
    mid = E[round(MIDDLE[0] * elements):round(MIDDLE[1] * elements)]
    r.update(model=model_name(LOCKINGS[model], load), E=(float(mid.min()), float(mid.max())), u_mean=u_mean,
             span=span, fit0=float(r["u"][0]), E_elements=np.stack([E.min(axis=1), E.max(axis=1)], axis=1))
    return r


def beam_runs(case: Case, tmp: str) -> list[dict]:
    return [run_beam(case, n, tmp, model, load) for load in LOADS for model in LOCKINGS for n in ELEMENTS]
