"""Hyperelastic bodies with contact by exact Lagrange multipliers: state, residual and Jacobian (dolfinx)."""
from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from ancf_verify.contact.faces import Faces
from ancf_verify.contact.interface import Interface
from ancf_verify.contact.tendon import ContactError
from ancf_verify.roots import root_conditions


class ContactBodies:
    """Hyperelastic bodies (one dolfinx mesh, one μ, K per cell tag) with Dirichlet faces, dead end
    tractions and frictionless contact interfaces enforced by Lagrange multipliers.

    dirichlet: [(facet tag, components or a root name of ancf_verify.roots)]; tractions: {facet tag: total force per unit load
    factor (3,)}; interfaces: [(name, slave facet tag, master facet tag)]; law: None, 'sliding'
    or 'unilateral'."""
    #: the factorisation of the Newton matrix (MUMPS): LDLᵀ of the symmetric saddle-point system
    #: (a subclass with an unsymmetric term, such as friction, uses "lu")
    factor = "cholesky"

    def __init__(self, msh, ct, ft, materials: dict, dirichlet, tractions: dict, interfaces=(),
                 law: str | None = "sliding", quad_degree: int = 2, rule_points: int = 3,
                 ks: float | None = None, kappa: float = 1.0, geometric: bool = True,
                 candidates: int = 24, penalty: float = 0.0):
        import ufl
        from petsc4py import PETSc
        from dolfinx import fem
        from dolfinx.fem.petsc import create_matrix
        self.msh, self.ct, self.ft = msh, ct, ft
        V = fem.FunctionSpace(msh, ufl.VectorElement("CG", msh.ufl_cell(), 2))
        self.V = V
        self.u = fem.Function(V)
        u, v, du = self.u, ufl.TestFunction(V), ufl.TrialFunction(V)
        Q = fem.FunctionSpace(msh, ("DG", 0))
        mu, K = fem.Function(Q), fem.Function(Q)
        qd = Q.dofmap.list.array
        for tag, (m, k) in materials.items():
            cells = ct.indices[ct.values == tag]
            mu.x.array[qd[cells]] = m
            K.x.array[qd[cells]] = k
        self.mu_ref = max(m for m, _ in materials.values())
        bcs = []
        for tag, comps in dirichlet:
            facets = ft.indices[ft.values == tag]
            if len(facets) == 0:
                raise ContactError(f"no facets with Dirichlet tag {tag}")
            if isinstance(comps, str):          # a named root support (ancf_verify.roots)
                bcs += root_conditions(V, msh, facets, comps)
            elif tuple(comps) == (0, 1, 2):
                bcs.append(fem.dirichletbc(np.zeros(3, dtype=PETSc.ScalarType),
                                           fem.locate_dofs_topological(V, 2, facets), V))
            else:
                for c in comps:
                    bcs.append(fem.dirichletbc(PETSc.ScalarType(0.0),
                                               fem.locate_dofs_topological(V.sub(c), 2, facets), V.sub(c)))
        self.bcs = bcs
        self.ndof = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
        mask = np.ones(self.ndof)
        for bc in bcs:
            mask[bc.dof_indices()[0]] = 0.0
        self.mask = mask
        md = {"quadrature_degree": quad_degree}
        dx = ufl.Measure("dx", domain=msh, metadata=md)
        ds = ufl.Measure("ds", domain=msh, subdomain_data=ft, metadata=md)
        F = ufl.Identity(3) + ufl.grad(u)
        J, I1 = ufl.det(F), ufl.tr(F.T * F)
        psi = mu / 2 * (J ** (-2.0 / 3.0) * I1 - 3) + K / 2 * (J - 1) ** 2
        self.tr_consts, self.tr_force, self.face_area = {}, {}, {}
        energy = psi * dx
        for tag, force in tractions.items():
            area = fem.assemble_scalar(fem.form(1.0 * ds(tag)))
            if area <= 0:
                raise ContactError(f"traction face {tag} not found")
            c = fem.Constant(msh, np.zeros(3, dtype=PETSc.ScalarType))
            self.tr_consts[tag], self.tr_force[tag], self.face_area[tag] = c, np.asarray(force, float), area
            energy = energy - ufl.dot(c, u) * ds(tag)
        self.ds, self.dx = ds, dx
        res = ufl.derivative(energy, u, v)
        self.E_form = fem.form(energy)
        self.F_form = fem.form(res)
        self.J_form = fem.form(ufl.derivative(res, u, du))
        self.A = create_matrix(self.J_form)
        self.b = self.u.vector.duplicate()
        self.X = V.tabulate_dof_coordinates().copy()
        self.law = law if interfaces else None
        self.geometric = geometric
        self.ifaces = []
        for name, st, mt in interfaces:
            fixed = mask.reshape(-1, 3).sum(axis=1) == 0
            self.ifaces.append(Interface(name, Faces(V, ft, st, self.X), Faces(V, ft, mt, self.X), self.X,
                                         rule_points, candidates, fixed))
        self.nc = sum(i.nc for i in self.ifaces)
        hmin = self._mesh_size()
        self.h = hmin
        self.ks = ks if ks is not None else self.mu_ref * hmin     # multiplier unit [N/m]
        self.kappa = kappa                                        # unilateral: ε = κ μ / h
        self.penalty = penalty      # > 0: either law by a pure penalty ε = penalty μ / h, no multipliers
        self.eps_pen = (penalty or kappa) * self.mu_ref / hmin
        self.ak_all = np.concatenate([i.ak for i in self.ifaces]) if self.ifaces else np.zeros(0)
        self.lam = np.zeros(self.nc)                              # Uzawa multipliers [Pa]
        self.restrict = None
        self.uzawa = {"outer": 0, "max_outer": 0}
        self.z = np.zeros(self.nc)
        self.alive = np.ones(self.nc, dtype=bool)
        self.active = np.ones(self.nc, dtype=bool) if self.law == "sliding" else np.zeros(self.nc, dtype=bool)
        self.set_passes, self.set_changes, self.set_unsettled = 0, 0, 0
        self.load = 0.0
        self.stall_tol = 1e-4
        self.debug = False
        self.stats = {"newton": 0, "factorizations": 0, "t_assemble": 0.0, "t_contact": 0.0, "t_solve": 0.0}

    def _mesh_size(self) -> float:
        """Mean edge length of the contact slave faces (or of the mesh), for scales."""
        if self.ifaces:
            nodes = np.vstack([i.slave.nodes for i in self.ifaces])
        else:
            dm = self.V.dofmap.list.array.reshape(-1, 10)
            return float(np.linalg.norm(self.X[dm[:, 0]] - self.X[dm[:, 1]], axis=1).mean())
        X = self.X
        e = [np.linalg.norm(X[nodes[:, a]] - X[nodes[:, b]], axis=1) for a, b in ((0, 1), (1, 2), (0, 2))]
        return float(np.mean(e))

    # ---------------------------------------------------------------------------------------
    def set_load(self, lam: float) -> None:
        self.load = lam
        for tag, c in self.tr_consts.items():
            c.value[:] = lam * self.tr_force[tag] / self.face_area[tag]

    def positions(self, uvec: np.ndarray) -> np.ndarray:
        return self.X + uvec.reshape(-1, 3)

    def _internal(self, uvec: np.ndarray, matrix: bool):
        """dolfinx residual (BC rows zero) and, if asked, the tangent as scipy CSR (BC rows/cols
        identity)."""
        from petsc4py import PETSc
        from dolfinx.fem.petsc import assemble_matrix, assemble_vector
        t0 = time.perf_counter()
        self.u.x.array[:] = uvec
        self.u.x.scatter_forward()
        with self.b.localForm() as loc:
            loc.set(0.0)
        assemble_vector(self.b, self.F_form)
        self.b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        r = self.b.array.copy() * self.mask
        Kc = None
        if matrix:
            self.A.zeroEntries()
            assemble_matrix(self.A, self.J_form, bcs=self.bcs)
            self.A.assemble()
            ip, ix, val = self.A.getValuesCSR()
            Kc = sp.csr_matrix((val.copy(), ix.copy(), ip.copy()), shape=(self.ndof, self.ndof))
        self.stats["t_assemble"] += time.perf_counter() - t0
        return r, Kc

    def contact(self, uvec: np.ndarray, z, matrix: bool) -> dict:
        """Weighted gaps, their gradient G (nc x ndof, BC columns zero), the contact forces
        −k_s Gᵀ z (dead constraints carry none) and, if asked, the geometric stiffness
        k_s Σ_q τ_q W C Wᵀ.  z may be a function of the weighted gaps (augmented Lagrangian)."""
        t0 = time.perf_counter()
        x = self.positions(uvec)
        gbar, Gs, evs, dofl = [], [], [], []
        for itf in self.ifaces:
            ev = itf.evaluate(x, hessian=matrix and self.geometric)
            evs.append(ev)
            dofs = itf.dofs(ev["mf"])
            dofl.append(dofs)
            gv = itf.grad_values(ev)
            Gq = sp.csr_matrix((gv.ravel(), dofs.ravel(), np.arange(0, 36 * itf.nq + 1, 36)),
                               shape=(itf.nq, self.ndof))
            gbar.append(itf.B @ ev["gr"])
            Gs.append(itf.B @ Gq)
        G = (sp.vstack(Gs).tocsr() @ sp.diags(self.mask)).tocsr() if Gs else sp.csr_matrix((0, self.ndof))
        gb = np.concatenate(gbar) if gbar else np.zeros(0)
        if callable(z):
            z = z(gb)
        za = np.where(self.alive, z, 0.0)
        r = -self.ks * (G.T @ za)
        Kg, rows0 = None, 0
        kg_rows, kg_cols, kg_vals = [], [], []
        for itf, ev, dofs in zip(self.ifaces, evs, dofl):
            if matrix and self.geometric:
                tau = self.ks * (itf.B.T @ za[rows0:rows0 + itf.nc])      # (nq,) point forces
                nzq = np.nonzero(tau)[0]
                if len(nzq):
                    # group the points of one (slave face, master face) pair: one 36 x 36 block each
                    key = itf.face_of_q[nzq] * len(itf.master) + ev["mf"][nzq]
                    order = np.argsort(key, kind="stable")
                    nzq = nzq[order]
                    key = key[order]
                    starts = np.flatnonzero(np.r_[True, key[1:] != key[:-1]])
                    W = itf.hess_W(ev)[nzq]
                    WC = np.matmul(W, ev["C"][nzq]) * tau[nzq, None, None]
                    blocks = np.add.reduceat(np.matmul(WC, np.swapaxes(W, 1, 2)), starts, axis=0)
                    d = dofs[nzq[starts]]
                    kg_rows.append(np.repeat(d, 36, axis=1).ravel())
                    kg_cols.append(np.tile(d, (1, 36)).ravel())
                    kg_vals.append(blocks.ravel())
            rows0 += itf.nc
        if matrix and self.geometric and kg_vals:
            Kg = sp.csr_matrix((np.concatenate(kg_vals), (np.concatenate(kg_rows), np.concatenate(kg_cols))),
                               shape=(self.ndof, self.ndof))
            Dm = sp.diags(self.mask)
            Kg = (Dm @ Kg @ Dm).tocsr()
        self.stats["t_contact"] += time.perf_counter() - t0
        return {"gbar": gb, "G": G, "r": r, "Kg": Kg, "evs": evs, "z": za}

    # ---------------------------------------------------------------------------------------
    def residual(self, uvec, z, matrix=False):
        """Sliding law: full residual [R_u; R_z], R_z = −k_s ḡ (dead constraints: −k_s z), and
        the symmetric saddle-point matrix [[K + K_geo, −k_s Gᵀ], [−k_s G, 0]] as CSR."""
        r, Kc = self._internal(uvec, matrix)
        if not np.all(np.isfinite(r)):
            return None, None, None
        if not self.ifaces:
            return r, (Kc if matrix else None), None
        c = self.contact(uvec, z, matrix)
        alive = self.alive
        c["active"] = alive.copy()
        rz = np.where(alive, -self.ks * c["gbar"], -self.ks * z)
        R = np.concatenate([r + c["r"], rz])
        if not matrix:
            return R, None, c
        Kt = Kc if c["Kg"] is None else (Kc + c["Kg"])
        Ga = (sp.diags(alive.astype(float)) @ c["G"]).tocsr()
        D = sp.diags(np.where(alive, 0.0, -self.ks))
        Jm = sp.bmat([[Kt, -self.ks * Ga.T], [-self.ks * Ga, D]], format="csr")
        c["corr"] = np.zeros(self.ndof)
        return R, Jm, c
