"""Calibration: fit config values of a model (key paths) to measured data, and say what the data
determine (``ancf-fit``; docs/calibration.md).

Modules: ``spec`` (the fit file), ``parameters`` (key paths, bounds, log scale), ``data`` (CSV
files), ``quantities`` (what a data set measures: the registry), ``sample`` (the weighted
residuals of one sample), ``log`` (samples.jsonl: every sample, resume), ``library`` (warm
starts), ``evaluate`` (samples solved in-process, spread over ranks), ``optimise`` (scipy's
least_squares and differential evolution), ``identify`` and ``profiles`` (standard errors,
correlations, profiles, verdicts), ``calibrate`` (the whole run), ``report`` and ``plots``
(files and figures), ``slurm`` (a job array over the starts of a multi-start fit).
(Importing the package loads no PETSc: ``calibrate`` and the modules that solve do, on use.)
"""
from .errors import CalibrationError, CalibrationInterrupted
from .spec import FitSpec, load_fit

__all__ = ["CalibrationError", "CalibrationInterrupted", "FitSpec", "load_fit", "calibrate", "data", "errors", "evaluate", "identify", "library", "log",
           "optimise", "parameters", "plots", "profiles", "quantities", "report", "sample", "slurm", "spec"]
