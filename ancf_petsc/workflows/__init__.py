"""Many runs: ``study`` (speed-accuracy Pareto studies), ``stability`` (maps of where methods
fail), ``accuracy`` and ``refinement`` (the coarsest mesh within a tolerance), ``sweep``
(parameter sweeps, local or as SLURM job arrays)."""

#: the sub-modules (imported on use: a plain import of the package loads none of them)
__all__ = ["accuracy", "refinement", "stability", "study", "sweep"]
