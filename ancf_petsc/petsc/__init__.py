"""The PETSc layer: ``problem`` (the residual and Jacobian SNES calls, in Vec/Mat), ``blocks``
(element blocks, node-block insertion), ``pattern`` (exact preallocation, growing with contact),
``exchange`` (the node blocks a rank reads), ``loading`` and ``reactions`` (applied loads,
prescribed displacements, support reactions), ``potential`` and ``step_limits`` (the energy,
rounding floor, near-null space; step-length limits), ``complementarity`` (the unilateral law's
predictor) and ``contact_reports`` (contact results over ranks).  The options database, the linear
solvers and the log events are in ``linalg``."""

#: the sub-modules (imported on use: a plain import of the package loads none of them)
__all__ = ["blocks", "complementarity", "contact_reports", "exchange", "loading", "pattern", "potential",
           "problem", "reactions", "step_limits"]
