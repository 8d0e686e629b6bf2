"""PETSc's options and the linear solvers, in one place (as dolfinx keeps ``la`` beside ``fem``):
``database`` (the only reader and writer of PETSc's options database), ``option_syntax`` (config
and command-line values checked the way PETSc parses them; pure Python, read by the config layer),
``options`` (a solve's defaults, the Jacobian's storage, setFromOptions with command line > config
> defaults), ``choice`` (which linear solver ``solver.linear`` takes, and why), ``diagnostics``
(unused options, PETSc and MUMPS errors as one line), ``inertia`` (MUMPS pivot counts), the fascicle
Schur solver (``fieldsplit``, ``fascicles``, ``substructure``, ``interface_system``,
``mumps_schur``) and ``logging`` (log stages and events, created on first use).  Importing the
package loads no PETSc: only the modules that need it import petsc4py."""

#: the sub-modules (imported on use)
__all__ = ["choice", "database", "diagnostics", "fascicles", "fieldsplit", "inertia", "interface_system",
           "log_view", "logging", "mumps_schur", "option_syntax", "options", "substructure"]
