"""Newton's method on the contact bodies: the linear solve, the contact set, plain and augmented Lagrangian."""
from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from ancf_verify.contact.tendon import ContactError
from ancf_verify.contact.bodies import ContactBodies


class ContactNewton(ContactBodies):
    """One load level of the contact bodies by Newton's method (MUMPS); ``factor`` says how."""

    def residual_alm(self, uvec, matrix=False):
        """Unilateral law, inner problem of the augmented Lagrangian: minimise
        E(u) = Π(u) + Σ_k a_k/(2ε) [max(0, λ_k − ε ḡ_k)² − λ_k²]  (λ fixed, ε = κ μ/h).
        Returns (R_u, matrix, c, E): R_u = ∇E (forces of p_k = max(0, λ_k − ε ḡ_k)), and the
        Newton matrix in the regularised saddle-point form [[K + K_geo, −k_s G_Aᵀ],
        [−k_s G_A, −k_s²/(a ε)]] (A: p_k > 0), whose Schur complement is the penalty Hessian
        K + K_geo + ε G_Aᵀ diag(a) G_A without forming G_Aᵀ G_A.  A pure penalty of the sliding
        law (``penalty`` > 0) is the same with p_k = λ_k − ε ḡ_k (tension too), every k in A."""
        r, Kc = self._internal(uvec, matrix)
        if not np.all(np.isfinite(r)):
            return None, None, None, None
        ak, eps, lam = self.ak_all, self.eps_pen, self.lam
        holder, bilateral = {}, bool(self.penalty) and self.law == "sliding"

        def zfun(gb):
            p = np.where(self.alive, lam - eps * gb if bilateral else np.maximum(0.0, lam - eps * gb), 0.0)
            holder["p"] = p
            return ak * p / self.ks
        c = self.contact(uvec, zfun, matrix)
        p = holder["p"]
        # generalised Hessian: at the kink λ − ε ḡ = 0 (the touching reference state) the
        # constraint counts as closed, so that a first step does not run into the penalty
        active = self.alive & (bilateral | (lam - eps * c["gbar"] >= -1e-12 * eps * self.h))
        c["active"], c["p"] = active, p
        R = r + c["r"]
        E = self._energy(uvec) + float(np.sum(ak / (2 * eps) * (p ** 2 - np.where(self.alive, lam, 0.0) ** 2)))
        if not matrix:
            return R, None, c, E
        Kt = Kc if c["Kg"] is None else (Kc + c["Kg"])
        Ga = (sp.diags(active.astype(float)) @ c["G"]).tocsr()
        D = sp.diags(np.where(active, -self.ks ** 2 / (ak * eps), -self.ks))
        Jm = sp.bmat([[Kt, -self.ks * Ga.T], [-self.ks * Ga, D]], format="csr")
        return R, Jm, c, E

    def _energy(self, uvec) -> float:
        from dolfinx import fem
        self.u.x.array[:] = uvec
        self.u.x.scatter_forward()
        return float(fem.assemble_scalar(self.E_form))

    def _solve_linear(self, Jm, rhs):
        from petsc4py import PETSc
        t0 = time.perf_counter()
        Jm.sort_indices()
        A = PETSc.Mat().createAIJ(size=Jm.shape, csr=(Jm.indptr.astype(PETSc.IntType),
                                                      Jm.indices.astype(PETSc.IntType), Jm.data))
        A.setOption(PETSc.Mat.Option.SYMMETRIC, self.factor == "cholesky")
        A.assemble()
        ksp = PETSc.KSP().create(PETSc.COMM_SELF)
        ksp.setType("preonly")
        pc = ksp.getPC()
        pc.setType(self.factor)
        pc.setFactorSolverType("mumps")
        ksp.setOperators(A)
        ksp.setUp()
        b = A.createVecLeft()
        b.array[:] = rhs
        x = A.createVecRight()
        ksp.solve(b, x)
        if ksp.getConvergedReason() < 0:
            raise ContactError(f"MUMPS failed (reason {ksp.getConvergedReason()})")
        out = x.array.copy()
        # destroy the factor and the PC explicitly: left to the garbage collector, petsc4py 3.18
        # keeps MUMPS's factors alive (tens of MB per factorization)
        pc.getFactorMatrix().destroy()
        pc.destroy()
        for o in (ksp, A, b, x):
            o.destroy()
        PETSc.garbage_cleanup()
        self.stats["factorizations"] += 1
        self.stats["t_solve"] += time.perf_counter() - t0
        return out

    def update_contact_set(self, uvec: np.ndarray, tol: float = 1e-6) -> int:
        """Re-decide which slave points are over their master (at uvec); returns how many changed.
        The set is frozen during a Newton solve (so that Newton sees a smooth problem) and
        updated after it until it no longer changes."""
        if not self.ifaces:
            return 0
        x = self.positions(uvec)
        changed = 0
        for itf in self.ifaces:
            ev = itf.evaluate(x, hessian=False)
            on = ~(ev["border"] & (ev["zout"] > tol))
            changed += int(np.sum(on != itf.on))
            if np.any(on != itf.on):
                itf.set_on(on)
        self.alive = np.concatenate([i.alive for i in self.ifaces])
        if self.restrict is not None:
            self.alive &= self.restrict
        self.active &= self.alive
        return changed

    def newton(self, uvec, z, rtol=1e-10, atol=1e-9, max_it=None):
        """Newton from (uvec, z) with residual-guarded steps (the sliding law, or exact multipliers on
        a given active set for the unilateral polish);
        the set of slave points over their master is updated at convergence (and Newton goes
        on if it changed).  Returns (ok, its, uvec, z)."""
        ndof = self.ndof
        if max_it is None:
            max_it = 60 if self.law == "unilateral" else 30
        R, Jm, c = self.residual(uvec, z, matrix=True)
        if R is None:
            return False, 0, uvec, z
        r0 = r = float(np.linalg.norm(R))
        set_updates, hist, floor = 0, [r0], False
        for it in range(max_it + 1):
            conv = r <= max(rtol * r0, atol)
            if conv or (it > 0 and floor):
                if self._settle_set(uvec, set_updates):
                    set_updates += 1
                    z = np.where(self.alive, z, 0.0)
                    R, Jm, c = self.residual(uvec, z, matrix=True)
                    r = float(np.linalg.norm(R))
                    floor, hist = False, [r]
                    continue
                if c is not None:
                    self.active = c["active"]
                return True, it, uvec, z
            if it == max_it:
                return False, it, uvec, z
            self.stats["newton"] += 1
            rhs = -R
            if c is not None:
                rhs[:ndof] -= c["corr"]
            d = self._solve_linear(Jm, rhs)
            step, accepted = 1.0, False
            while step >= 1.0 / 32:
                u_t = uvec + step * d[:ndof]
                z_t = z + step * d[ndof:] if self.nc else z
                # the full step is usually taken: assemble its tangent at once
                R_t, J_t, c_t = self.residual(u_t, z_t, matrix=step == 1.0)
                if R_t is not None:
                    r_t = float(np.linalg.norm(R_t))
                    if r_t < r or (r < 1e-6 * r0 and r_t < 10 * r) or (step < 1.0 / 16 and r_t < 2 * r):
                        accepted = True
                        break
                step *= 0.5
            if not accepted:
                return False, it + 1, uvec, z
            # rounding / kink floor: a slave point on an edge between two master faces makes the
            # residual only piecewise smooth; below 1e-6 of the applied force that is noise
            fs = max(r0, self.load * sum(float(np.linalg.norm(f)) for f in self.tr_force.values()))
            floor = (r < 1e-7 * r0 or r < 1e-6 * fs) and r_t > 0.5 * r
            # kink floor: a slave point whose closest master face switches makes the contact
            # force jump by (point force) x (kink angle between the deformed master faces), and
            # Newton can cycle between the two sides.  Accepted (and counted) when five
            # iterations no longer halve the residual and it is below 1e-4 of the applied force
            hist.append(r_t)
            if not floor and len(hist) > 5 and min(hist[-5:]) > 0.5 * hist[-6] and r_t < self.stall_tol * fs:
                floor = True
                self.stats["stalls"] = self.stats.get("stalls", 0) + 1
                self.stats["stall_max"] = max(self.stats.get("stall_max", 0.0), r_t / fs)
            if self.debug:
                extra = ""
                if c_t is not None:
                    nb = sum(int(e["border"].sum()) for e in c_t["evs"])
                    extra = f" border {nb} active {int(c_t['active'].sum())}/{self.nc}"
                print(f"      it {it + 1}: |R| {r_t:.3e} (u {np.linalg.norm(R_t[:ndof]):.2e}, "
                      f"z {np.linalg.norm(R_t[ndof:]):.2e}) step {step:g}{extra} "
                      f"|du| {np.abs(d[:ndof]).max():.2e}", flush=True)
            uvec, z = u_t, z_t
            if J_t is not None:
                R, Jm, c = R_t, J_t, c_t
            else:
                R, Jm, c = self.residual(uvec, z, matrix=True)
            r = float(np.linalg.norm(R))
        return False, max_it, uvec, z

    def newton_alm(self, uvec, rtol=1e-10, atol=1e-9, max_it=40):
        """Newton on the inner augmented-Lagrangian problem (λ fixed): steps guarded by the
        energy E or the residual (as verify_solid.Newton); the slave-point set is updated at
        convergence.  Returns (ok, its, uvec, c)."""
        ndof = self.ndof
        R, Jm, c, E = self.residual_alm(uvec, matrix=True)
        if R is None:
            return False, 0, uvec, None
        r0 = r = float(np.linalg.norm(R))
        fs = max(r0, self.load * sum(float(np.linalg.norm(f)) for f in self.tr_force.values()))
        set_updates, floor = 0, False
        for it in range(max_it + 1):
            if r <= max(rtol * r0, atol) or floor:
                if self._settle_set(uvec, set_updates):
                    set_updates += 1
                    R, Jm, c, E = self.residual_alm(uvec, matrix=True)
                    r, floor = float(np.linalg.norm(R)), False
                    continue
                return True, it, uvec, c
            if it == max_it:
                return False, it, uvec, c
            self.stats["newton"] += 1
            d = self._solve_linear(Jm, np.concatenate([-R, np.zeros(self.nc)]))[:ndof]
            step, accepted = 1.0, False
            while step >= 1.0 / 256:
                u_t = uvec + step * d
                R_t, J_t, c_t, E_t = self.residual_alm(u_t, matrix=step == 1.0)
                if R_t is not None:
                    r_t = float(np.linalg.norm(R_t))
                    if E_t < E or r_t < r:
                        accepted = True
                        break
                step *= 0.5
            if not accepted:
                return False, it + 1, uvec, c
            floor = (r < 1e-7 * r0 or r < 1e-6 * fs) and r_t > 0.5 * r
            if self.debug:
                print(f"      it {it + 1}: |R| {r_t:.3e} E {E_t:.9e} step {step:g} "
                      f"active {int(c_t['active'].sum())}/{self.nc} |du| {np.abs(d).max():.2e}", flush=True)
            uvec = u_t
            if J_t is not None:
                R, Jm, c, E = R_t, J_t, c_t, E_t
            else:
                R, Jm, c, E = self.residual_alm(uvec, matrix=True)
            r = float(np.linalg.norm(R))
        return False, max_it, uvec, c
