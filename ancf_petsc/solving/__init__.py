"""Solving a model: ``options`` (the SNES/KSP/PC options and the Jacobian's storage), ``stepper``
(Newton with line search inside adaptive load stepping), ``run`` (one run from spec to results,
its PETSc objects destroyed at the end), ``supports`` (rigid motions left free), ``interrupt``
(signals between Newton solves)."""

#: the sub-modules (imported on use: a plain import of the package loads none of them)
__all__ = ["chord", "interrupt", "linear", "newton", "options", "records", "restart_check", "run", "samples",
           "solver_messages", "spread", "stepper", "supports"]
