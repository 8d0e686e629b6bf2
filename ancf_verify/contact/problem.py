"""The contact problem of the solid: load paths with cut-backs, and what is read from a solution."""
from __future__ import annotations

import numpy as np

from ancf_verify.contact.tendon import ContactError
from ancf_verify.contact.newton import ContactNewton


class Problem(ContactNewton):
    """Hyperelastic bodies with Dirichlet faces, dead end tractions and frictionless contact interfaces
    enforced by Lagrange multipliers (ContactBodies), solved along a load path."""

    def solve_alm(self, uvec, tol_gap=None, max_outer=60):
        """Unilateral law: Uzawa iterations λ ← max(0, λ − ε ḡ) around newton_alm.  Once the
        update is small (max |Δλ|/ε < 1e-3 h, or the active set A = {λ > 0} unchanged over two
        updates), the active set is polished exactly: Lagrange multipliers on A (ḡ_A = 0, the
        sliding solver), the rest free; accepted when its pressures are ≥ 0 (to 1e-3 of the
        largest) and the free constraints do not penetrate (ḡ ≥ −1e-6 h): the discrete
        unilateral solution, independent of ε.  Otherwise Uzawa goes on (to max |Δλ|/ε <
        tol_gap = 1e-6 h).  Returns (ok, its, u)."""
        tol_gap = 1e-6 * self.h if tol_gap is None else tol_gap
        its, A_prev, same = 0, None, 0
        for outer in range(max_outer):
            ok, n, uvec, c = self.newton_alm(uvec)
            its += n
            if not ok:
                return False, its, uvec
            p = c["p"]
            viol = float(np.max(np.abs(p - np.where(self.alive, self.lam, 0.0)))) / self.eps_pen \
                if self.nc else 0.0
            self.lam = p.copy()
            self.uzawa["outer"] += 1
            A = p > 0
            same = same + 1 if A_prev is not None and np.array_equal(A, A_prev) else 0
            A_prev = A
            if self.debug:
                print(f"    Uzawa {outer + 1}: max |Δλ|/ε = {viol:.2e} m, active {int(A.sum())}/{self.nc}",
                      flush=True)
            if viol < tol_gap:
                self.uzawa["max_outer"] = max(self.uzawa["max_outer"], outer + 1)
                return True, its, uvec
            if viol < 1e-3 * self.h or same >= 2:
                okp, n, up = self._polish(uvec, A)
                its += n
                if okp:
                    self.uzawa["polished"] = self.uzawa.get("polished", 0) + 1
                    self.uzawa["max_outer"] = max(self.uzawa["max_outer"], outer + 1)
                    return True, its, up
        return False, its, uvec

    def _polish(self, uvec, A):
        """Exact Lagrange multipliers on the active set A (the rest free); checks the signs."""
        z0 = np.where(A, self.ak_all * self.lam / self.ks, 0.0)
        self.restrict = A.copy()
        self.alive = self.alive & A
        try:
            ok, n, u1, z1 = self.newton(uvec, z0)
        finally:
            self.restrict = None
            self.alive = np.concatenate([i.alive for i in self.ifaces])
        if not ok:
            return False, n, uvec
        p = self.ks * z1 / self.ak_all
        gb = self.contact(u1, np.zeros(self.nc), False)["gbar"]
        free = self.alive & ~A
        pmax = max(float(p[A].max()) if A.any() else 0.0, 1e-30)
        good = (not A.any() or p[A].min() >= -1e-3 * pmax) and (not free.any() or gb[free].min() >= -1e-6 * self.h)
        if self.debug:
            print(f"    polish on {int(A.sum())} constraints: p min {p[A].min() if A.any() else 0:.3e} Pa, "
                  f"free gap min {gb[free].min() if free.any() else 0:.3e} m -> {'accepted' if good else 'rejected'}",
                  flush=True)
        if not good:
            return False, n, uvec
        self.lam = np.where(A & self.alive, np.maximum(p, 0.0), 0.0)
        return True, n, u1

    def _settle_set(self, uvec, updates: int) -> bool:
        """At a converged Newton iterate: update the set of slave points over their master;
        True if it changed (Newton then goes on from here with the new set).  After 3 updates
        the set is kept (points that toggle at the master's edge are counted as unsettled)."""
        if not self.ifaces:
            return False
        if updates >= 3:
            x = self.positions(uvec)
            for itf in self.ifaces:
                ev = itf.evaluate(x, hessian=False)
                self.set_unsettled += int(np.sum(~(ev["border"] & (ev["zout"] > 1e-6)) != itf.on))
            return False
        ch = self.update_contact_set(uvec)
        if ch:
            self.set_passes += 1
            self.set_changes += ch
        return ch > 0

    def _increment(self, u0, z0):
        """One load increment from (u0, z0): (ok, its, u, z).  With ``penalty``: one solve of the
        penalty problem (λ = 0, no Uzawa update, no polish); its pressures are kept in ``lam``."""
        if self.penalty:
            self.lam = np.zeros(self.nc)
            ok, n, u1, c = self.newton_alm(u0)
            if ok:
                self.lam = c["p"].copy()
            return ok, n, u1, self.ak_all * self.lam / self.ks
        if self.law == "unilateral":
            ok, n, u1 = self.solve_alm(u0)
            return ok, n, u1, self.ak_all * self.lam / self.ks
        return self.newton(u0, z0)

    def solve_path(self, levels, on_level=None, first_increment=None, max_increment=None,
                   max_cutbacks=10, predictor=True, log=None):
        """Load stepping through ``levels`` (load factors) with cut-backs and a secant predictor.
        Calls on_level(level, its) after each converged level.  Returns total Newton iterations."""
        self.uvec, self.zvec, self.load_done = np.zeros(self.ndof), np.zeros(self.nc), 0.0
        uvec = np.zeros(self.ndof)
        z = np.zeros(self.nc)
        lam = 0.0
        prev = None                 # (lam, u, z) of the state before the last converged one
        dlam = first_increment or levels[0]
        its_total, cutbacks = 0, 0
        for level in levels:
            its_level = 0
            while lam < level - 1e-12:
                trial = min(lam + dlam, level)
                if max_increment:
                    trial = min(trial, lam + max_increment)
                if level - trial < 1e-9 * level:
                    trial = level
                self.set_load(trial)
                u0, z0 = uvec, z
                if predictor and prev is not None and lam - prev[0] > 0:
                    s = (trial - lam) / (lam - prev[0])
                    u0, z0 = uvec + s * (uvec - prev[1]), z + s * (z - prev[2])
                on0 = [i.on.copy() for i in self.ifaces]
                self.update_contact_set(uvec)
                act0, lam0 = self.active.copy(), self.lam.copy()
                ok, n, u1, z1 = self._increment(u0, z0)
                if not ok and u0 is not uvec:       # predictor may have overshot: plain start
                    self.active, self.lam = act0, lam0.copy()
                    its_total += n
                    its_level += n
                    ok, n, u1, z1 = self._increment(uvec, z)
                its_total += n
                its_level += n
                if ok:
                    prev = (lam, uvec, z)
                    lam, uvec, z = trial, u1, z1
                    if n <= 6:
                        dlam = dlam * 1.5
                    cutbacks = 0
                else:
                    for i, o in zip(self.ifaces, on0):
                        i.set_on(o)
                    if self.ifaces:
                        self.alive = np.concatenate([i.alive for i in self.ifaces])
                    self.active, self.lam = act0, lam0
                    dlam = 0.5 * (trial - lam)
                    cutbacks += 1
                    if log:
                        log(f"    cut back at {trial:.4g} (Newton {n} its) -> increment {dlam:.4g}")
                    if cutbacks > max_cutbacks or dlam < 1e-6 * max(level, 1.0):
                        raise ContactError(f"Newton failed at load factor {trial:.4g}")
            self.uvec, self.zvec = uvec, z
            self.load_done = level
            if on_level:
                on_level(level, its_level)
        self.uvec, self.zvec = uvec, z
        return its_total

    # ---------------------------------------------------------------------------------------
    def point_values(self, pts: np.ndarray, cell_tag: int) -> np.ndarray:
        """u at reference points (n, 3) inside the body with cell tag ``cell_tag``."""
        from dolfinx import geometry
        self.u.x.array[:] = self.uvec
        self.u.x.scatter_forward()
        body = set(self.ct.indices[self.ct.values == cell_tag].tolist())
        tree = geometry.BoundingBoxTree(self.msh, self.msh.topology.dim)
        cells = geometry.compute_colliding_cells(self.msh, geometry.compute_collisions(tree, pts), pts)
        out = []
        for i in range(len(pts)):
            cs = [c for c in cells.links(i) if c in body]
            if not cs:
                raise ContactError(f"point {pts[i]} not found in body {cell_tag}")
            out.append(np.asarray(self.u.eval(pts[i:i + 1], np.array([cs[0]], dtype=np.int32)),
                                  float).ravel())
        return np.array(out)

    def face_mean(self, tag: int) -> np.ndarray:
        """Mean displacement over a tagged face (reference area)."""
        from dolfinx import fem
        self.u.x.array[:] = self.uvec
        self.u.x.scatter_forward()
        a = fem.assemble_scalar(fem.form(1.0 * self.ds(tag)))
        return np.array([fem.assemble_scalar(fem.form(self.u[i] * self.ds(tag))) / a for i in range(3)])

    def gap_report(self) -> dict:
        """Pointwise |g − g0| (max, rms), weighted gaps, pressure range, active count."""
        if not self.ifaces:
            return {}
        c = self.contact(self.uvec, self.zvec, False)
        on = np.concatenate([i.on for i in self.ifaces])
        g = np.concatenate([ev["gr"] for ev in c["evs"]])[on]
        w = np.concatenate([i.w for i in self.ifaces])[on]
        ak = np.concatenate([i.ak for i in self.ifaces])
        p = self.ks * self.zvec / ak
        act = (self.lam > 0) if self.law == "unilateral" or self.penalty else self.active
        return {"g_max": float(np.abs(g).max()), "g_rms": float(np.sqrt(np.sum(w * g ** 2) / w.sum())),
                "gbar_max_active": float(np.abs(c["gbar"][act]).max()) if act.any() else 0.0,
                "gbar_min": float(c["gbar"][self.alive].min()),
                "p_min": float(p.min()), "p_max": float(p.max()), "active": int(act.sum()), "nc": self.nc,
                "alive": int(self.alive.sum()), "off": int((~on).sum()),
                "set_passes": self.set_passes, "set_unsettled": self.set_unsettled,
                "nq": int(sum(i.nq for i in self.ifaces))}
