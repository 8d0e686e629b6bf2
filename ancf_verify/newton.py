"""Newton's method on a dolfinx nonlinear problem with MUMPS, load stepping with cut-backs."""
from __future__ import annotations

import numpy as np


class Newton:
    """Newton on dolfinx forms with MUMPS LDLT and a guarded step.

    A full step is taken when it lowers the total potential energy or the residual norm;
    otherwise (or when an element inverts: NaN energy) it is halved, down to 1/64.  The energy
    test alone stalls near convergence (a Newton step's energy change falls below the energy's
    rounding, ~|F|^2/k), the residual test alone follows saddle paths far from it.  Converged:
    |F| <= max(rtol |F_0|, atol), or |F| <= floor_rtol |F_0| and a full step no longer halves
    it (the rounding floor of the residual)."""

    def __init__(self, u, bcs, E_form, F_form, J_form, rtol=1e-9, atol=0.0, max_it=25,
                 floor_rtol=1e-6):
        from petsc4py import PETSc
        from dolfinx.fem.petsc import create_matrix
        self.u, self.bcs, self.E, self.F, self.J = u, bcs, E_form, F_form, J_form
        self.rtol, self.atol, self.max_it, self.floor_rtol = rtol, atol, max_it, floor_rtol
        self.A = create_matrix(J_form)
        self.b, self.dx = u.vector.duplicate(), u.vector.duplicate()
        self.ksp = PETSc.KSP().create(u.function_space.mesh.comm)
        self.ksp.setOptionsPrefix("solid_")
        opts = PETSc.Options()
        for k, val in {"ksp_type": "preonly", "pc_type": "cholesky",
                       "pc_factor_mat_solver_type": "mumps"}.items():
            opts.setValue("solid_" + k, val)
        self.ksp.setOperators(self.A)
        self.ksp.setFromOptions()

    def _residual(self) -> float:
        from petsc4py import PETSc
        from dolfinx.fem.petsc import apply_lifting, assemble_vector, set_bc
        x, b = self.u.vector, self.b
        x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
        with b.localForm() as loc:
            loc.set(0.0)
        assemble_vector(b, self.F)
        apply_lifting(b, [self.J], bcs=[self.bcs], x0=[x], scale=-1.0)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        set_bc(b, self.bcs, x, -1.0)
        return b.norm()

    def _energy(self) -> float:
        from dolfinx import fem
        self.u.x.scatter_forward()
        return self.u.function_space.mesh.comm.allreduce(fem.assemble_scalar(self.E))

    def solve(self) -> tuple[bool, int]:
        """Solve from the current u (which satisfies the BCs); (converged, iterations)."""
        from dolfinx.fem.petsc import assemble_matrix
        x = self.u.vector
        r = r0 = self._residual()
        for it in range(self.max_it + 1):
            if not np.isfinite(r):
                return False, it
            if r <= max(self.rtol * r0, self.atol):
                return True, it
            if it == self.max_it:
                return False, it
            self.A.zeroEntries()
            assemble_matrix(self.A, self.J, bcs=self.bcs)
            self.A.assemble()
            self.ksp.solve(self.b, self.dx)           # dx = -K^-1 F after the sign below
            self.dx.scale(-1.0)
            e0, step = self._energy(), 1.0
            while True:
                x.axpy(step, self.dx)
                e, r_new = self._energy(), self._residual()
                if np.isfinite(e) and np.isfinite(r_new) and (e < e0 or r_new < r):
                    if r < self.floor_rtol * r0 and r_new > 0.5 * r:
                        return True, it + 1               # rounding floor reached
                    r = r_new
                    break
                x.axpy(-step, self.dx)
                step *= 0.5
                if step < 1.0 / 64:
                    return False, it + 1
        return False, self.max_it
