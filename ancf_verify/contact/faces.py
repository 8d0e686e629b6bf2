"""Master faces, closest-point projection of slave points and the weighted-gap terms."""
from __future__ import annotations

import numpy as np

from ancf_verify.contact.quadrature import D2N, p2_shape
from ancf_verify.contact.tendon import ContactError


# ============================================================================================
# Contact: faces, projection, gap and its derivatives
# ============================================================================================
class Faces:
    """P2 boundary faces with one facet tag: node (block) indices (n, 6) in P2-triangle order,
    oriented so that t1 x t2 points out of the body."""

    def __init__(self, V, ft, tag: int, X: np.ndarray):
        import basix
        msh = V.mesh
        tdim = msh.topology.dim
        facets = ft.indices[ft.values == tag]
        if len(facets) == 0:
            raise ContactError(f"no facets with tag {tag}")
        msh.topology.create_connectivity(tdim - 1, tdim)
        msh.topology.create_connectivity(tdim, tdim - 1)
        f2c, c2f = msh.topology.connectivity(tdim - 1, tdim), msh.topology.connectivity(tdim, tdim - 1)
        cells = np.array([f2c.links(f)[0] for f in facets], dtype=np.int64)
        c2f_arr = c2f.array.reshape(-1, 4)
        local = np.argmax(c2f_arr[cells] == facets[:, None], axis=1)
        layout = V.dofmap.dof_layout
        vdof = [layout.entity_dofs(0, v)[0] for v in range(4)]
        edges = basix.topology(basix.CellType.tetrahedron)[1]
        edof = {tuple(sorted(e)): layout.entity_dofs(1, i)[0] for i, e in enumerate(edges)}
        table = np.zeros((4, 6), dtype=np.int64)      # local facet -> 6 cell-local dofs
        opp = np.zeros((4,), dtype=np.int64)
        for i in range(4):
            a, b, c = [v for v in range(4) if v != i]
            table[i] = [vdof[a], vdof[b], vdof[c], edof[(b, c)], edof[(a, c)], edof[(a, b)]]
            opp[i] = vdof[i]
        dm = V.dofmap.list.array.reshape(-1, 10)
        nodes = dm[cells[:, None], table[local]]
        opp_nodes = dm[cells, opp[local]]
        # orient outwards: normal at the face centre against the opposite vertex
        N, dN = p2_shape(np.array([1 / 3, 1 / 3]))
        Xf = X[nodes]
        t = np.einsum("ab,nai->nbi", dN, Xf)
        nrm = np.cross(t[:, 0], t[:, 1])
        inward = np.einsum("ni,ni->n", nrm, np.einsum("a,nai->ni", N, Xf) - X[opp_nodes]) < 0
        nodes[inward] = nodes[inward][:, [0, 2, 1, 3, 5, 4]]
        self.nodes = nodes
        self.tag = tag

    def __len__(self):
        return len(self.nodes)


def project(xq: np.ndarray, Y: np.ndarray, cand: np.ndarray, iters: int = 40, clip: bool = True,
            z0=None):
    """Closest points of xq (n, 3) on the P2 faces Y (m, 6, 3), searched over cand (n, k):
    Gauss-Newton in z per (point, face), clipped to the triangle; returns the best face (n,) and z
    (n, 2) and whether that z is on the face's border (clipped)."""
    n, k = cand.shape
    Yc = Y[cand].reshape(n * k, 6, 3)
    P = np.repeat(xq, k, axis=0)
    z = np.full((n * k, 2), 1.0 / 3.0) if z0 is None else np.repeat(z0, k, axis=0)
    todo = np.arange(n * k)
    for _ in range(iters):
        Yt, zt = Yc[todo], z[todo]
        N, dN = p2_shape(zt)
        x = np.matmul(N[:, None, :], Yt)[:, 0, :]
        T = np.matmul(np.swapaxes(dN, -1, -2), Yt)          # (m, 2, 3)
        r = P[todo] - x
        rhs = np.matmul(T, r[:, :, None])[:, :, 0]
        A = np.matmul(T, np.swapaxes(T, -1, -2))
        det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] ** 2
        dz = np.stack([A[:, 1, 1] * rhs[:, 0] - A[:, 0, 1] * rhs[:, 1],
                       A[:, 0, 0] * rhs[:, 1] - A[:, 0, 1] * rhs[:, 0]], axis=-1) / det[:, None]
        znew = clip_tri(zt + dz) if clip else zt + dz
        moved = np.abs(znew - zt).max(axis=1) > 1e-15
        z[todo] = znew
        todo = todo[moved]
        if len(todo) == 0:
            break
    N, _ = p2_shape(z)
    d = np.linalg.norm(P - np.matmul(N[:, None, :], Yc)[:, 0, :], axis=1).reshape(n, k)
    best = np.argmin(d, axis=1)
    zb = z.reshape(n, k, 2)[np.arange(n), best]
    border = (zb.min(axis=1) < 1e-12) | (zb.sum(axis=1) > 1 - 1e-12)
    return cand[np.arange(n), best], zb, border


def project_free(xq: np.ndarray, Y: np.ndarray, cand: np.ndarray, iters: int = 40) -> np.ndarray:
    """Unclipped Gauss-Newton feet of xq (n, 3) on the smooth extensions of the P2 faces
    Y[cand] (n, k): z (n, k, 2), NaN where it does not converge."""
    n, k = cand.shape
    Yc = Y[cand].reshape(n * k, 6, 3)
    P = np.repeat(xq, k, axis=0)
    z = np.full((n * k, 2), 1.0 / 3.0)
    for _ in range(iters):
        N, dN = p2_shape(z)
        x = np.matmul(N[:, None, :], Yc)[:, 0, :]
        T = np.matmul(np.swapaxes(dN, -1, -2), Yc)
        r = P - x
        rhs = np.matmul(T, r[:, :, None])[:, :, 0]
        A = np.matmul(T, np.swapaxes(T, -1, -2))
        det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] ** 2
        dz = np.stack([A[:, 1, 1] * rhs[:, 0] - A[:, 0, 1] * rhs[:, 1],
                       A[:, 0, 0] * rhs[:, 1] - A[:, 0, 1] * rhs[:, 0]], axis=-1) / det[:, None]
        dz = np.clip(dz, -0.5, 0.5)
        z = z + dz
        if np.nanmax(np.abs(dz)) < 1e-15:
            break
    z[~(np.abs(dz).max(axis=1) < 1e-10)] = np.nan
    return z.reshape(n, k, 2)


def clip_tri(z):
    z = np.maximum(z, 0.0)
    s = z.sum(axis=-1)
    over = s > 1.0
    if np.any(over):
        # closest point on the hypotenuse z1 + z2 = 1 (then clipped to its ends)
        d = 0.5 * (z[..., 0] - z[..., 1])
        z1 = np.clip(0.5 + d, 0.0, 1.0)
        z[over] = np.stack([z1, 1.0 - z1], axis=-1)[over]
    return z


def gap_terms(xs: np.ndarray, Ym: np.ndarray, z: np.ndarray, hessian: bool):
    """Gap g = (xs − x_m(z))·n and, per point, the master shape values (n, 6), the unit outward
    normal (n, 3), and for the Hessian W (n, 36, 4) and C (n, 4, 4) with ∇²g = −W C Wᵀ (slave
    rows 0-17 filled by the caller's slave shape values)."""
    N, dN = p2_shape(z)
    x = np.einsum("na,nai->ni", N, Ym)
    T = np.einsum("nab,nai->nbi", dN, Ym)
    c = np.cross(T[:, 0], T[:, 1])
    nrm = c / np.linalg.norm(c, axis=1)[:, None]
    r = xs - x
    g = np.einsum("ni,ni->n", r, nrm)
    out = {"g": g, "N": N, "dN": dN, "n": nrm, "T": T}
    if hessian:
        X2 = np.einsum("abc,nai->nbci", D2N, Ym)
        a = np.einsum("nbi,nci->nbc", T, T)
        b = np.einsum("nbci,ni->nbc", X2, nrm)
        H = a - g[:, None, None] * b
        Hi, ai = np.linalg.inv(H), np.linalg.inv(a)
        C = np.zeros((len(g), 4, 4))
        C[:, :2, :2] = ai @ b @ Hi
        C[:, :2, 2:] = Hi
        C[:, 2:, :2] = Hi
        C[:, 2:, 2:] = g[:, None, None] * Hi
        out["C"] = 0.5 * (C + np.transpose(C, (0, 2, 1)))
    return out
