"""Synthetic twins: data made by the program itself from known parameters plus known noise, to
check that a fit recovers what made the data and that its standard errors are honest
(docs/calibration.md; tests/workflows/test_calibration_twin.py; scripts/bench_calibration.py).

The model is solved once at the true values (cold, like ancf-solve); each draw adds independent
Gaussian noise of the data sets' own σ to its exact quantities.  ``coverage`` counts, over draws,
how often the true value lies within k standard errors of the fitted one.
"""
from __future__ import annotations

import copy
from dataclasses import replace

import numpy as np

from ...config.parse import parse_config
from ...solving.samples import SampleSolver
from .sample import model_values
from .spec import FitSpec


def exact_data(spec: FitSpec, values) -> dict[str, np.ndarray]:
    """Every data set's quantity of the model at parameter values ``values`` (one cold solve)."""
    solver = SampleSolver()
    try:
        out = solver.solve(parse_config(spec.config(values), base_dir=spec.model_dir))
    finally:
        solver.destroy()
    if out.status != "completed":
        raise RuntimeError(f"the twin's model did not solve at the true values: {out.message}")
    return model_values(spec, out)


def with_data(spec: FitSpec, data: dict[str, np.ndarray], output: str | None = None) -> FitSpec:
    """A copy of ``spec`` whose data sets hold ``data`` (same levels and σ)."""
    out = copy.copy(spec)
    out.data = [replace(d, values=np.asarray(data[d.name], dtype=float)) for d in spec.data]
    if output is not None:
        out.output = output
    return out


def draw(spec: FitSpec, exact: dict[str, np.ndarray], rng: np.random.Generator) -> dict[str, np.ndarray]:
    """One noisy copy of the exact data (Gaussian, each point its data set's σ)."""
    return {d.name: exact[d.name] + rng.normal(0.0, d.sigmas) for d in spec.data}


def coverage(true: np.ndarray, fitted: np.ndarray, se: np.ndarray, k: float) -> np.ndarray:
    """(draws, parameters): whether |fitted − true| <= k SE, per draw and parameter."""
    return np.abs(np.asarray(fitted) - np.asarray(true)[None, :]) <= k * np.asarray(se)
