"""One contact interface of the solid: slave Gauss points, partners, weighted gaps and their derivatives."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ancf_verify.contact.faces import Faces, gap_terms, project, project_free
from ancf_verify.contact.quadrature import p2_shape, slave_rule


class Interface:
    """One slave/master pair: slave Gauss points, hats (weighted-gap matrix), reference gaps."""

    def __init__(self, name, slave: Faces, master: Faces, X: np.ndarray, rule_points: int,
                 candidates: int = 24, fixed=None):
        self.name, self.slave, self.master = name, slave, master
        zq, wq, corners, hats = slave_rule(rule_points)
        self.Q = len(wq)
        Ns, dNs = p2_shape(zq)                               # (Q, 6), (Q, 6, 2)
        self.Ns = Ns
        Xs = X[slave.nodes]                                  # (nf, 6, 3)
        T = np.einsum("qab,fai->fqbi", dNs, Xs)
        jac = np.linalg.norm(np.cross(T[:, :, 0], T[:, :, 1]), axis=2)   # (nf, Q)
        w = (jac * wq[None, :]).ravel()                      # reference area weights
        nf = len(slave)
        self.face_of_q = np.repeat(np.arange(nf), self.Q)
        self.area = float(w.sum())
        # constraint k = unique slave node; B_kq = w_q φ_k(q) / Σ_q w_q φ_k(q).  Slave nodes whose
        # displacement is prescribed (the clamped root) carry no multiplier: their gap is fixed
        # already, and a constraint there would over-constrain the first row of elements (as in
        # mortar methods, the removed hat is shared out to the free corners of its sub-triangle,
        # which keeps the partition of unity)
        cn = slave.nodes[:, corners].reshape(-1, 3)          # (nf Q, 3) node ids of the hat corners
        beta = np.broadcast_to(hats, (nf, self.Q, 3)).reshape(-1, 3).copy()
        if fixed is not None:
            rem = fixed[cn]
            nfree = 3 - rem.sum(axis=1)
            extra = np.where(nfree > 0, (beta * rem).sum(axis=1) / np.maximum(nfree, 1), 0.0)
            beta = np.where(rem, 0.0, beta + extra[:, None])
        keep = beta.ravel() > 0
        self.cnodes, inv = np.unique(cn.ravel()[keep], return_inverse=True)
        rows = inv
        cols = np.repeat(np.arange(nf * self.Q), 3)[keep]
        vals = (w[:, None] * beta).ravel()[keep]
        Braw = sp.csr_matrix((vals, (rows, cols)), shape=(len(self.cnodes), nf * self.Q))
        self.ak = np.asarray(Braw.sum(axis=1)).ravel()
        self.Braw = Braw
        self.w = w
        self.set_on(np.ones(nf * self.Q, dtype=bool))
        self.candidates = candidates
        self.edge_band = 0.02
        self.g0, self.last_mf, self.track = None, None, True
        self.g0 = self.evaluate(X, hessian=False)["g"].copy()

    def set_on(self, on: np.ndarray) -> None:
        """Which slave points are over the master surface (in contact).  A point past the master's
        edge (its end, or the edge of the interface strip after sliding across it) has nothing
        to touch and leaves the constraints; a constraint whose points are all off is dead."""
        self.on = on.copy()
        self.B = (sp.diags(1.0 / self.ak) @ self.Braw @ sp.diags(on.astype(float))).tocsr()
        self.frac = (self.Braw @ on.astype(float)) / self.ak
        self.alive = self.frac > 1e-3

    @property
    def nq(self):
        return len(self.face_of_q)

    @property
    def nc(self):
        return len(self.cnodes)

    def slave_points(self, x: np.ndarray) -> np.ndarray:
        return np.einsum("qa,fai->fqi", self.Ns, x[self.slave.nodes]).reshape(-1, 3)

    def evaluate(self, x: np.ndarray, hessian: bool) -> dict:
        """Project the slave points of configuration x (nodes, 3) and evaluate gaps (and Hessian terms)."""
        from scipy.spatial import cKDTree
        xs = self.slave_points(x)
        Ym = x[self.master.nodes]
        Nc, _ = p2_shape(np.array([1 / 3, 1 / 3]))
        cent = np.einsum("a,fai->fi", Nc, Ym)
        # phase 1: the face of the last projection (or the nearest centroid); an interior foot
        # point there is the closest point (the interface is smooth on the scale of the gap)
        first = self.last_mf if self.last_mf is not None else \
            cKDTree(cent).query(xs, k=1)[1].astype(np.int64)
        mf, z, border = project(xs, Ym, first[:, None])
        far = np.zeros(len(xs), dtype=bool)
        # phase 2 also for interior feet close to a face edge: where the deformed P2 surface
        # has a concave kink, a point near the edge has an interior foot on both faces, and
        # keeping the last face would make the gap depend on the iteration history (Newton then
        # cycles between two states); the closest of the candidates is history-free
        near = border | (np.minimum(z.min(axis=1), 1.0 - z.sum(axis=1)) < self.edge_band)
        if np.any(near):
            # phase 2: search the k nearest faces (and the last one), keep the closest foot
            b = np.nonzero(near)[0]
            k = min(self.candidates, len(cent))
            cand = cKDTree(cent).query(xs[b], k=k)[1].reshape(len(b), k)
            cand = np.hstack([first[b, None], cand])
            mf[b], z[b], border[b] = project(xs[b], Ym, cand)
            # points off the master surface (past its end or the edge of the interface strip):
            # foot point on the smooth extension of the nearest face (unclipped), so that g and
            # its derivatives stay smooth and consistent
            # Of the candidates, the face whose unclipped foot is least outside it (not the
            # first of equally close clipped feet on a shared edge, which would depend on the
            # candidate order, i.e. on the history).
            row = np.full(len(xs), -1, dtype=np.int64)
            row[b] = np.arange(len(b))
            b = np.nonzero(border)[0]
            if len(b):
                cb = cand[row[b]]                                   # (nb, k + 1)
                zu = project_free(xs[b], Ym, cb)                    # (nb, k + 1, 2)
                out_by = np.maximum(-zu.min(axis=2), zu.sum(axis=2) - 1.0)
                out_by = np.where(np.isfinite(out_by), out_by, np.inf)
                j = np.argmin(out_by, axis=1)
                sel = np.arange(len(b))
                best_out = out_by[sel, j]
                ok = best_out < 0.5
                mf[b[ok]] = cb[sel, j][ok]
                z[b[ok]] = zu[sel, j][ok]
                far[b[~ok]] = True           # too far past the edge to extrapolate: off anyway
        if self.track:
            self.last_mf = mf.copy()
        out = gap_terms(xs, Ym[mf], z, hessian)
        out.update(mf=mf, z=z, border=border, xs=xs,
                   zout=np.where(far, 1.0, np.maximum(0.0, np.maximum(-z.min(axis=1), z.sum(axis=1) - 1.0))))
        if self.g0 is not None:
            out["gr"] = out["g"] - self.g0
        return out

    def dofs(self, mf: np.ndarray) -> np.ndarray:
        """(nq, 36) DOF indices: slave face nodes then master face nodes, xyz each."""
        nodes = np.hstack([self.slave.nodes[self.face_of_q], self.master.nodes[mf]])   # (nq, 12)
        return (3 * nodes[:, :, None] + np.arange(3)).reshape(len(mf), 36)

    def grad_values(self, ev: dict) -> np.ndarray:
        """(nq, 36) ∇g per point: slave N_i n, master −M_a n."""
        Ns = self.Ns[np.tile(np.arange(self.Q), len(self.slave))]          # (nq, 6)
        gs = Ns[:, :, None] * ev["n"][:, None, :]
        gm = -ev["N"][:, :, None] * ev["n"][:, None, :]
        return np.hstack([gs.reshape(-1, 18), gm.reshape(-1, 18)])

    def hess_W(self, ev: dict) -> np.ndarray:
        """W (nq, 36, 4) of ∇²g = −W C Wᵀ: columns U_α (slave N_i t_α, master −M_a t_α) and
        V_α (slave 0, master M_a,α n)."""
        Ns = self.Ns[np.tile(np.arange(self.Q), len(self.slave))]
        T, N, dN, n = ev["T"], ev["N"], ev["dN"], ev["n"]
        W = np.zeros((len(N), 12, 3, 4))
        W[:, :6, :, 0:2] = np.einsum("na,nbi->naib", Ns, T)
        W[:, 6:, :, 0:2] = -np.einsum("na,nbi->naib", N, T)
        W[:, 6:, :, 2:4] = np.einsum("nab,ni->naib", dN, n)
        return W.reshape(len(N), 36, 4)
