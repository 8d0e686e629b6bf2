"""Element kernels batched over (elements × Gauss points) — pure numpy, no PETSc.

Shapes are written for element 3363 (S = 18 shape functions, 54 DOFs); every kernel takes the
slot count from G, so element 3333 (S = 9, 27 DOFs) runs through the same code.

With scalar shape functions the deformation gradient is F = Σ_a q_a ⊗ G_a (G_a = ∇₀N_a, eq. 7),
the internal force is f_a = Σ_gp w P G_a and the tangent K_ab = Σ_gp w G_a · 𝔸 · G_b: the virtual
work ∫ S : δE dV of eq. (14) written with P = F S.  ``w`` already holds det J0 and the axial ×
section cubature weights.  Every product below is a batched matrix product over the element's
Gauss points, so the cost per Gauss point is a few small GEMM columns and no Python loop.

The neo-Hookean and GOH laws (pointwise, without ``locking: mixed``) run in the compiled kernels
of ``element_kernels.pyx`` when they are built (``ancf_petsc.native``; ``ANCF_NATIVE=0`` switches
them off); this numpy code is the reference they are tested against (tests/physics).
"""
from __future__ import annotations

import numpy as np

from .. import native
from .goh import GOH
from .materials import NeoHookean, TangentTerms

#: the Cython module of the compiled kernels (``native.load``)
COMPILED = "physics.element_kernels"


def compiled_law(material, shape: tuple[int, int]) -> tuple | None:
    """(module, law parameters, fibre directions (families, E, P, 3) or None) when the compiled
    kernels compute ``material`` on points of ``shape`` (E, P); None for the numpy path."""
    module = native.load(COMPILED)
    if module is None:
        return None
    kind = type(material)
    if kind is NeoHookean or (kind is GOH and not material.k1):      # k1 = 0: the matrix alone
        return module, (material.mu, material.K, 0.0, 0.0, 0.0, 0.0), None
    if kind is GOH and material.a0 is not None:
        a0 = np.broadcast_to(material.a0, (material.families,) + tuple(shape) + (3,))
        return module, (material.mu, material.K, material.k1, material.k2, material.kappa,
                        material.e_rounding), a0
    return None


def deformation_gradient(qe: np.ndarray, G: np.ndarray) -> np.ndarray:
    """F (E, P, 3, 3) from nodal vectors qe (E, 18, 3) and gradients G (E, P, 18, 3) (eq. 7):
    one (3 × 18)(18 × 3P) product per element on the stacked gradients (``_stack``; free for
    the shape-function-major G of ``Model.element_data``), 3x faster than one per point."""
    E, P = G.shape[:2]
    F = np.matmul(np.swapaxes(qe, 1, 2), _stack(G)).reshape(E, 3, P, 3)
    return np.ascontiguousarray(F.transpose(0, 2, 1, 3))


def _stack(G: np.ndarray) -> np.ndarray:
    """(E, P, 18, 3) → (E, 18, 3P): shape functions × (points, components)."""
    E, P = G.shape[:2]
    return G.transpose(0, 2, 1, 3).reshape(E, G.shape[2], 3 * P)


def energy(qe: np.ndarray, G: np.ndarray, w: np.ndarray, material) -> np.ndarray:
    """Strain energy per element (E,)."""
    return np.sum(w * material.energy(deformation_gradient(qe, G)), axis=1)


def internal_force(qe, G, w, material) -> tuple[np.ndarray, np.ndarray]:
    """Internal forces (E, 54) and min J per element (E,); f_a = Σ w P G_a."""
    fast = compiled_law(material, w.shape)
    if fast is not None:
        f, _, J = fast[0].evaluate(qe, G, w, fast[1], fast[2], False)
        return f, J
    F = deformation_gradient(qe, G)
    P, J = material.stress(F)
    E, Np = w.shape
    wP = (w[..., None, None] * P).transpose(0, 1, 3, 2).reshape(E, 3 * Np, 3)
    f = np.matmul(_stack(G), wP)
    return f.reshape(E, 3 * G.shape[2]), np.min(J, axis=1)


#: Gauss points per batch: keeps the temporaries of the tangent in cache (and out of mmap);
#: measured best between ~300 and ~600 on this machine (scripts/bench_kernel.py)
CHUNK_POINTS = 400


def internal_force_and_tangent(qe, G, w, material) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Internal forces (E, 54), tangents (E, 54, 54) and min J per element (E,).

    Elements are processed in chunks of about ``CHUNK_POINTS`` Gauss points (a law with data
    per point, e.g. GOH's fibre directions, gives the chunk's with ``material.take``); the
    compiled kernels take all elements at once (their scratch is one element's).
    """
    fast = compiled_law(material, w.shape)
    if fast is not None:
        return fast[0].evaluate(qe, G, w, fast[1], fast[2], True)
    E, Np = w.shape
    step = max(1, CHUNK_POINTS // Np)
    if E <= step:
        return _force_and_tangent(qe, G, w, material)
    D = 3 * G.shape[2]
    f, K, J = np.empty((E, D)), np.empty((E, D, D)), np.empty(E)
    for s in range(0, E, step):
        sl = slice(s, s + step)
        f[sl], K[sl], J[sl] = _force_and_tangent(qe[sl], G[sl], w[sl], material.take(sl))
    return f, K, J


def _force_and_tangent(qe, G, w, material):
    F = deformation_gradient(qe, G)
    P, J, terms = material.stress_and_tangent(F)
    E, Np = w.shape
    Gs = _stack(G)
    wP = (w[..., None, None] * P).transpose(0, 1, 3, 2).reshape(E, 3 * Np, 3)
    f = np.matmul(Gs, wP).reshape(E, 3 * G.shape[2])
    return f, contract_tangent(terms, G, w), np.min(J, axis=1)


def _times_gradients(B, G: np.ndarray, along) -> np.ndarray:
    """(B G_a) (E, P, S, 3) for a 3×3 field B, or for a pair (u, v) meaning u ⊗ v: u (v · G_a)."""
    if isinstance(B, tuple):      # (E, P, S, 1)(E, P, 1, 3): 2x faster than the broadcast product
        u, v = B
        return np.matmul(along(v)[..., None], u[:, :, None, :])
    return np.matmul(G, np.swapaxes(B, -1, -2))


def _identity_part(terms: TangentTerms, G: np.ndarray, w: np.ndarray, along):
    """The terms with δ_ik, Σ_p w G_aj S_jl G_bl (E, S, S): ``iso`` and ``rank_one``, or None."""
    Ks = None
    if terms.iso is not None:
        wcol = w[..., None, None]
        if terms.iso.ndim == 2:      # scalar field c: δ_ik c δ_jl
            right = (wcol * terms.iso[..., None, None]) * G
        else:                         # δ_ik S_jl
            right = np.matmul(G, np.swapaxes(terms.iso, -1, -2)) * wcol
        Ks = np.matmul(_stack(G), _stack(right).transpose(0, 2, 1))
    for c, a in terms.rank_one:      # δ_ik c (G_a · a)(G_b · a)
        Ga = along(a)
        K1 = np.matmul(Ga.transpose(0, 2, 1), (w * c)[..., None] * Ga)
        Ks = K1 if Ks is None else Ks + K1
    return Ks


def _side(BG: list, sd, weight=None, out=None) -> np.ndarray:
    """Σ c (B_k G_a) (× weight) as (E, P, D) from the products BG (each (E, P, D)), into ``out``
    if given; a coefficient is an array over the points, a number, or None (1)."""
    out = np.empty(BG[0].shape) if out is None else out
    for n, (c, k) in enumerate(sd):
        coef = c if weight is None else (weight if c is None else c * weight)
        src = BG[k]
        if coef is not None:
            coef = np.asarray(coef)[..., None] if np.ndim(coef) else coef   # a number as is
        if coef is None:
            if n == 0:
                out[...] = src
            else:
                out += src
        elif n == 0:
            np.multiply(coef, src, out=out)
        else:
            out += coef * src
    return out


def _outer_gemm(terms: TangentTerms, BG: list, w: np.ndarray) -> np.ndarray | None:
    """Σ X ⊗ Y + Σ c T ⊗ T as (E, D, D) in one GEMM whose inner dimension stacks (term, point);
    a square's T G_a is formed once (c on the left, w on the right).  None if there are none."""
    n_outer = len(terms.outer)
    m = n_outer + len(terms.squares)
    if not m:
        return None
    E, Np, D = BG[0].shape
    left, right = np.empty((E, m * Np, D)), np.empty((E, m * Np, D))
    for t, (X, Y) in enumerate(terms.outer):
        _side(BG, X, out=left[:, t * Np:(t + 1) * Np])
        _side(BG, Y, w, out=right[:, t * Np:(t + 1) * Np])
    for t, (c, T) in enumerate(terms.squares, start=n_outer):
        blk_l, blk_r = left[:, t * Np:(t + 1) * Np], right[:, t * Np:(t + 1) * Np]
        _side(BG, T, out=blk_r)                                      # T G_a, once
        np.multiply(c[..., None], blk_r, out=blk_l)
        blk_r *= w[..., None]
    return np.matmul(left.transpose(0, 2, 1), right)


def contract_tangent(terms: TangentTerms, G: np.ndarray, w: np.ndarray) -> np.ndarray:
    """K[(a,i),(b,k)] = Σ_p w G_aj 𝔸_ijkl G_bl for the dyadic form of 𝔸 (see materials.py).

    Each basis tensor B is multiplied with the gradients once, (B G_a)_i; every outer term
    X ⊗ Y then contributes Σ_p (X G_a)_i w (Y G_b)_k, and all of them, with the squares, go into
    one GEMM (``_outer_gemm``).  Cross terms U ⊠ V give Σ_p (U G_b)_i w (V G_a)_k.
    """
    E, Np = w.shape
    S = G.shape[2]
    D = 3 * S
    projections = {}

    def along(a):
        """G_a · a (E, P, S), once per direction array (a fibre's a0 serves two terms)."""
        if id(a) not in projections:
            projections[id(a)] = np.matmul(G, a[..., None])[..., 0]
        return projections[id(a)]

    BG = [_times_gradients(B, G, along).reshape(E, Np, D) for B in terms.basis]
    Kf = _outer_gemm(terms, BG, w)
    if Kf is None:
        Kf = np.zeros((E, D, D))
    for C, Q, X in terms.projected:  # Σ_kl b_k C_kl b_l, b_k = Σ_p Q_pk (X G_a)_p: (E, m, D)
        XG = BG[X[0][1]] if len(X) == 1 and X[0][0] is None else _side(BG, X)     # no copy of one basis
        b = np.matmul(np.swapaxes(Q, -1, -2), XG)
        Kf += np.matmul(np.swapaxes(b, -1, -2), np.matmul(C, b))
    for U, V in terms.cross:
        M = np.matmul(_side(BG, V).transpose(0, 2, 1), _side(BG, U, w)).reshape(E, S, 3, S, 3)
        Kf += M.transpose(0, 1, 4, 3, 2).reshape(E, D, D)
    K = Kf.reshape(E, S, 3, S, 3)
    idx = np.arange(3)
    Ks = _identity_part(terms, G, w, along)
    if Ks is not None:
        K[:, :, idx, :, idx] += Ks[None]
    if terms.gram is not None:       # (G_a · G_b) B_ik
        GG = np.matmul(G, np.swapaxes(G, -1, -2)).reshape(E, Np, S * S)
        wB = (w[..., None, None] * terms.gram).reshape(E, Np, 9)
        K += np.matmul(GG.transpose(0, 2, 1), wB).reshape(E, S, S, 3, 3).transpose(0, 1, 3, 2, 4)
    return Kf
