"""The contact solid with Coulomb friction: reference partners, return mapping, consistent tangent."""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ancf_verify.contact.problem import Problem
from ancf_verify.contact.quadrature import D2N, p2_shape
from ancf_verify.contact.tendon import ContactError


def normal_gradient(Ns: np.ndarray, ev: dict, Ym: np.ndarray) -> np.ndarray:
    """∂n/∂u (P, 3, 36) over (slave face, current master face) of the unit master normal at the
    closest point, the closest point moving with u: H ∂ζ = Uᵀ + g Vᵀ (W = [U V] as in
    Interface.hess_W; Ns (P, 6) the slave shape values of the points)."""
    T, n, g, dN, N = ev["T"], ev["n"], ev["g"], ev["dN"], ev["N"]
    X2 = np.einsum("abc,nai->nbci", D2N, Ym)                     # (P, 2, 2, 3)
    a = np.einsum("nbi,nci->nbc", T, T)
    b = np.einsum("nbci,ni->nbc", X2, n)
    Hi = np.linalg.inv(a - g[:, None, None] * b)
    W = np.zeros((len(N), 12, 3, 4))
    W[:, :6, :, 0:2] = np.einsum("na,nbi->naib", Ns, T)
    W[:, 6:, :, 0:2] = -np.einsum("na,nbi->naib", N, T)
    W[:, 6:, :, 2:4] = np.einsum("nab,ni->naib", dN, n)
    W = W.reshape(len(N), 36, 4)
    dz = np.einsum("nab,nkb->nak", Hi, W[:, :, 0:2] + g[:, None, None] * W[:, :, 2:4])   # (P, 2, 36)
    P = len(n)
    dT = np.zeros((P, 2, 3, 12, 3))
    for i in range(3):
        dT[:, :, i, 6:, i] = np.transpose(dN, (0, 2, 1))             # master node a: M_a,α e_i
    dT = dT.reshape(P, 2, 3, 36) + np.einsum("nabi,nbk->naik", X2, dz)
    dc = (np.cross(dT[:, 0], T[:, 1][:, :, None], axis=1)
          + np.cross(T[:, 0][:, :, None], dT[:, 1], axis=1))         # (P, 3, 36)
    c = np.linalg.norm(np.cross(T[:, 0], T[:, 1]), axis=1)
    proj = np.eye(3)[None] - n[:, :, None] * n[:, None, :]
    return np.matmul(proj, dc) / c[:, None, None]


def grouped(keys: np.ndarray, rows: np.ndarray, cols: np.ndarray, blocks: np.ndarray):
    """COO triplets of per-point dense blocks (P, r, c), summed over the points of equal key
    (points of one face pair share their DOFs)."""
    order = np.argsort(keys, kind="stable")
    k = keys[order]
    starts = np.flatnonzero(np.r_[True, k[1:] != k[:-1]])
    B = np.add.reduceat(blocks[order], starts, axis=0)
    r, c = rows[order[starts]], cols[order[starts]]
    nr, nc = r.shape[1], c.shape[1]
    return np.repeat(r, nc, axis=1).ravel(), np.tile(c, (1, nr)).ravel(), B.ravel()


class InterfaceFriction:
    """Friction state and kinematics of one interface: reference partners, σ₀, d₀ per point."""

    def __init__(self, itf, X: np.ndarray):
        self.itf = itf
        track, last = itf.track, itf.last_mf
        itf.track = False
        ev = itf.evaluate(X, hessian=False)
        itf.track, itf.last_mf = track, last
        self.mf0, self.z0 = ev["mf"].copy(), ev["z"].copy()
        self.N0, _ = p2_shape(self.z0)                            # (nq, 6)
        nodes = np.hstack([itf.slave.nodes[itf.face_of_q], itf.master.nodes[self.mf0]])
        self.dofs0 = (3 * nodes[:, :, None] + np.arange(3)).reshape(len(self.mf0), 36)
        self.Ns = itf.Ns[np.tile(np.arange(itf.Q), len(itf.slave))]    # (nq, 6)
        self.sigma0 = np.zeros((itf.nq, 3))
        self.d0 = self.relative(X)
        self.d_ref = self.d0.copy()                                  # d of the reference state
        self.x_ref = itf.slave_points(X)[:, 0]                        # reference axial position
        # closest point of the last accepted state (slip = "closest")
        self.mf_n, self.z_n = ev["mf"].copy(), ev["z"].copy()

    def relative(self, x: np.ndarray) -> np.ndarray:
        """d = x_s − x_m(ζ₀) (nq, 3) of configuration x (nodes, 3)."""
        xs = self.itf.slave_points(x)
        return xs - np.einsum("qa,qai->qi", self.N0, x[self.itf.master.nodes[self.mf0]])

    def closest_increment(self, x: np.ndarray):
        """x_s − x_m(ζ_n) (nq, 3), its master shape values and face (slip = "closest")."""
        N, _ = p2_shape(self.z_n)
        xs = self.itf.slave_points(x)
        return xs - np.einsum("qa,qai->qi", N, x[self.itf.master.nodes[self.mf_n]]), N, self.mf_n


def return_map(sigma0, a_incr, n, bound, k):
    """σ = proj_{|σ| ≤ bound}(P (σ₀ + k Δ)) and its derivatives (friction.py's mapping)."""
    a = sigma0 + k * a_incr
    na = np.einsum("pi,pi->p", n, a)
    trial = a - na[:, None] * n
    size = np.linalg.norm(trial, axis=1)
    stick = (size <= bound) & (bound > 0.0)
    slide = ~stick & (size > 0.0) & (bound > 0.0)
    t = np.zeros_like(trial)
    t[slide] = trial[slide] / size[slide, None]
    sigma = np.where(stick[:, None], trial, bound[:, None] * t)
    ratio = np.where(slide, bound / np.where(slide, size, 1.0), 0.0)
    eye = np.eye(3)[None]
    S = stick[:, None, None] * eye + ratio[:, None, None] * (eye - t[:, :, None] * t[:, None, :])
    P = eye - n[:, :, None] * n[:, None, :]
    dtrial_dn = -(na[:, None, None] * eye + n[:, :, None] * a[:, None, :])
    return {"sigma": sigma, "stick": stick, "slide": slide, "dsig_dd": k * S @ P,
            "dsig_dn": S @ dtrial_dn, "t": t}


class FrictionProblem(Problem):
    """The solid tendon with the sliding normal law and Coulomb friction at the slave points."""
    factor = "lu"

    def __init__(self, *args, mu: float = 0.3, stick: float = 100.0, slip: str = "partner",
                 free_zone: float = 0.0, **kw):
        super().__init__(*args, **kw)
        #: a diagnostic: no friction at slave points whose reference x is below this [m]
        self.free_zone = float(free_zone)
        if slip not in ("partner", "closest"):
            raise ContactError(f"slip measure {slip!r}: partner or closest")
        self.mu, self.slip = float(mu), slip
        self.k_stick = stick * self.mu_ref / self.h                 # [Pa/m]
        self.fr = [InterfaceFriction(i, self.X) for i in self.ifaces]
        self.fstats = {}

    # ------------------------------------------------------------------ evaluation
    def friction(self, uvec, c: dict, matrix: bool) -> dict:
        """Friction forces (ndof,) and, if asked, the Jacobian blocks (ndof x ndof, ndof x nc)."""
        x = self.positions(uvec)
        za = c["z"]
        f = np.zeros(self.ndof)
        rows, cols, vals, zr, zc, zv = [], [], [], [], [], []
        per, row0 = [], 0
        for fr, ev in zip(self.fr, c["evs"]):
            itf = fr.itf
            zi = za[row0:row0 + itf.nc]
            pk = np.where(self.alive[row0:row0 + itf.nc], self.ks * zi / itf.ak, 0.0)
            p = (itf.Braw.T @ pk) / itf.w
            bound = np.where(itf.on & (fr.x_ref >= self.free_zone), self.mu * np.maximum(p, 0.0), 0.0)
            if self.slip == "partner":
                incr, Nm, mfm = fr.relative(x) - fr.d0, fr.N0, fr.mf0
            else:
                incr, Nm, mfm = fr.closest_increment(x)
            rm = return_map(fr.sigma0, incr, ev["n"], bound, self.k_stick)
            sig = rm["sigma"]
            grad = np.hstack([fr.Ns, -Nm])                               # (nq, 12): ∇d = grad ⊗ I
            dofs_d = (3 * np.hstack([itf.slave.nodes[itf.face_of_q], itf.master.nodes[mfm]])[:, :, None]
                      + np.arange(3)).reshape(itf.nq, 36)
            force = (itf.w[:, None, None] * grad[:, :, None] * sig[:, None, :]).reshape(itf.nq, 36)
            f += np.bincount(dofs_d.ravel(), force.ravel(), minlength=self.ndof)
            per.append({"sigma": sig, "stick": rm["stick"], "slide": rm["slide"], "p": p, "on": itf.on,
                        "d": fr.relative(x), "mf": ev["mf"], "z": ev["z"]})
            act = np.nonzero(bound > 0.0)[0]
            if matrix and len(act):
                G3 = np.einsum("qa,ij->qaij", grad[act], np.eye(3)).reshape(len(act), 36, 3)   # ∇dᵀ
                wG = itf.w[act, None, None] * G3
                Kdd = wG @ rm["dsig_dd"][act] @ np.transpose(G3, (0, 2, 1))
                key = itf.face_of_q[act] * len(itf.master) + mfm[act]
                r, cc, v = grouped(key, dofs_d[act], dofs_d[act], Kdd)
                rows.append(r), cols.append(cc), vals.append(v)
                Ym = x[itf.master.nodes[ev["mf"]]]
                dn = normal_gradient(fr.Ns[act], {k: ev[k][act] for k in ("T", "n", "g", "dN", "N")}, Ym[act])
                Kdn = wG @ rm["dsig_dn"][act] @ dn
                dofs_n = itf.dofs(ev["mf"])[act]
                key = (itf.face_of_q[act] * len(itf.master) + mfm[act]) * len(itf.master) + ev["mf"][act]
                r, cc, v = grouped(key, dofs_d[act], dofs_n, Kdn)
                rows.append(r), cols.append(cc), vals.append(v)
                # ∂σ/∂p ∂p/∂z_k: slip points only, ∂p_q/∂z_k = k_s φ_k(q) / a_k (alive k)
                dsp = self.mu * rm["t"][act] * rm["slide"][act, None]               # (A, 3)
                colv = (wG @ dsp[:, :, None])[:, :, 0]                              # (A, 36)
                A = sp.csr_matrix((colv.ravel(), (dofs_d[act].ravel(), np.repeat(act, 36))),
                                  shape=(self.ndof, itf.nq))
                dpdz = (sp.diags(1.0 / itf.w) @ itf.Braw.T
                        @ sp.diags(np.where(self.alive[row0:row0 + itf.nc], self.ks / itf.ak, 0.0))).tocsr()
                Kz = (A @ dpdz).tocoo()
                zr.append(Kz.row), zc.append(Kz.col + row0), zv.append(Kz.data)
            row0 += itf.nc
        out = {"f": f * self.mask, "per": per}
        if matrix:
            Dm = sp.diags(self.mask)
            cat = (lambda a: np.concatenate(a)) if rows else (lambda a: np.zeros(0))
            Kuu = sp.csr_matrix((cat(vals), (cat(rows), cat(cols))), shape=(self.ndof, self.ndof))
            catz = (lambda a: np.concatenate(a)) if zr else (lambda a: np.zeros(0, dtype=int))
            Kuz = sp.csr_matrix((catz(zv), (catz(zr), catz(zc))), shape=(self.ndof, self.nc))
            out["Kuu"], out["Kuz"] = (Dm @ Kuu @ Dm).tocsr(), (Dm @ Kuz).tocsr()
        return out

    def residual(self, uvec, z, matrix=False):
        """The sliding law's saddle-point residual and matrix (verify_solid_contact.Problem) with
        the friction forces and their (unsymmetric) Jacobian added."""
        R, Jm, c = super().residual(uvec, z, matrix)
        if R is None or c is None:
            return R, Jm, c
        fr = self.friction(uvec, c, matrix)
        R = R.copy()
        R[:self.ndof] += fr["f"]
        c["friction"] = fr
        if matrix:
            Jm = (Jm + sp.bmat([[fr["Kuu"], fr["Kuz"]], [None, sp.csr_matrix((self.nc, self.nc))]])).tocsr()
        return R, Jm, c

    # ------------------------------------------------------------------ history
    def _increment(self, u0, z0):
        """One load increment; on success its friction state becomes the history (σ₀, d₀, ζ_n)."""
        ok, n, u1, z1 = super()._increment(u0, z0)
        if ok:
            self.accept(u1, z1)
        return ok, n, u1, z1

    def accept(self, uvec, z) -> None:
        c = Problem.residual(self, uvec, z, False)[2]
        fr = self.friction(uvec, c, False)
        x = self.positions(uvec)
        for f, per in zip(self.fr, fr["per"]):
            f.sigma0 = per["sigma"].copy()
            f.d0 = f.relative(x)
            f.mf_n, f.z_n = per["mf"].copy(), per["z"].copy()
        self.fstats = self.friction_report(fr["per"], uvec)

    def friction_report(self, per: list, uvec) -> dict:
        """Stick share of the pressed area, friction force on the slaves (x), largest relative
        displacement of a point and its partner since the reference state."""
        out = {}
        for fr, p in zip(self.fr, per):
            w = fr.itf.w
            pressed = p["on"] & (p["p"] > 0)
            area = float(w[pressed].sum())
            out[fr.itf.name] = {"stick_share": float(w[p["stick"]].sum()) / area if area else 0.0,
                                "pressed_share": area / float(w[p["on"]].sum()),
                                "force_x": float(-(w @ p["sigma"])[0]),
                                "max_rel_disp": float(np.linalg.norm(p["d"] - fr.d_ref, axis=1).max())}
        return out

    def gap_report(self) -> dict:
        rep = super().gap_report()
        rep["friction"] = dict(self.fstats)
        return rep
