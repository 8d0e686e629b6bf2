"""The PETSc layer: ``problem`` (the residual and Jacobian SNES calls, in Vec/Mat), ``blocks``
(element blocks, node-block insertion), ``pattern`` (exact preallocation, growing with contact),
``exchange`` (the node blocks a rank reads), ``contact_reports`` (contact results over ranks),
``inertia`` (MUMPS pivot counts), ``options`` (unused options, PETSc errors as one line) and
``logging`` (log stages and events, created on first use)."""

#: the sub-modules (imported on use: a plain import of the package loads none of them)
__all__ = ["blocks", "complementarity", "contact_reports", "exchange", "fascicles", "fieldsplit",
           "inertia", "interface_system", "logging", "mumps_schur", "options", "pattern",
           "problem", "substructure"]
