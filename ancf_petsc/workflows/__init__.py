"""Many runs: ``study`` (speed-accuracy Pareto studies), ``stability`` (maps of where methods
fail), ``accuracy`` and ``refinement`` (the coarsest mesh within a tolerance), ``sweep``
(parameter sweeps, local or as SLURM job arrays), ``calibration`` (fitting config values to
measured data, ancf-fit), ``iteration_bench`` (the cost of a Newton iteration of the paper's tendon
against older checkouts, scripts/bench_iteration.py), ``kernel_bench`` (the element kernels,
compiled beside numpy, scripts/bench_kernel.py)."""

#: the sub-modules (imported on use: a plain import of the package loads none of them)
__all__ = ["accuracy", "calibration", "iteration_bench", "kernel_bench", "refinement", "stability", "study", "sweep"]
