"""One evaluated parameter set and its weighted residuals (the objective).

The objective is weighted least squares: the residual of a data point is (model − measured) / σ,
the cost ½ Σ r² (``objective.loss`` may make scipy's least_squares robust to outliers).  A sample
that did not reach a level (SNES failure, an inverted element, an unstable state, a value the
model config refuses) keeps the residuals of the levels it reached and gets ``penalty`` (in σ)
at every other one, so the optimiser steps back from it; its status and reason code are recorded
as the solver reports them (``status.py``), never read from a message.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .quantities import QUANTITIES, evaluate
from .spec import FitSpec

if TYPE_CHECKING:                      # the solving layer loads PETSc
    from ...solving.samples import SampleOutcome


@dataclass
class Sample:
    """What the log keeps of one sample (``log.py``)."""
    index: int
    phase: str                     # fit | de | profile:<name> | start:<k>
    u: list[float]                 # the optimiser's coordinates
    parameters: dict[str, float]   # physical values
    status: str                    # completed | failed | unstable | config_error
    reason_code: str
    message: str
    residuals: list[float]         # (model − data) / σ, data set after data set; penalties included
    model: dict[str, list]         # data set → model values at its levels (NaN: not reached)
    inverted: bool = False
    levels_reached: int = 0
    newton_iterations: int = 0
    start: str = "cold"            # how it was started: cold | nearest | affine (library.py)
    warm_levels: int = 0
    fallbacks: int = 0
    rebuilt: bool = False
    wall_time: float = 0.0
    cpu_time: float = 0.0
    rank: int = 0
    extra: dict = field(default_factory=dict)
    #: [level, reported at]: levels the solve reported past a gap of the load path (step_over.py)
    passed_over: list = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return self.status == "completed"

    @property
    def r(self) -> np.ndarray:
        return np.asarray(self.residuals, dtype=float)

    @property
    def cost(self) -> float:
        """½ Σ r² (penalties included)."""
        return 0.5 * float(np.sum(self.r ** 2))

    def record(self) -> dict:
        """The sample as plain JSON (NaN model values as null)."""
        rec = asdict(self)
        rec["model"] = {k: [float(x) if np.isfinite(x) else None for x in v] for k, v in self.model.items()}
        return rec

    @classmethod
    def from_record(cls, rec: dict) -> "Sample":
        fields = cls.__dataclass_fields__
        s = cls(**{k: v for k, v in rec.items() if k in fields})
        s.model = {k: [np.nan if x is None else x for x in v] for k, v in s.model.items()}
        return s


def data_residuals(spec: FitSpec, model: dict[str, np.ndarray]) -> np.ndarray:
    """(model − data) / σ over every data set; ``penalty`` where the model has no value."""
    r = np.concatenate([(model[d.name] - d.values) / d.sigmas for d in spec.data])
    return np.where(np.isfinite(r), r, spec.penalty)


def model_values(spec: FitSpec, outcome: SampleOutcome) -> dict[str, np.ndarray]:
    """Every data set's quantity from a sample's probes (NaN at levels it did not reach)."""
    n = len(outcome.load_factors)
    disp = {}
    for name, u in outcome.displacements.items():
        full = np.full((len(spec.levels), 3), np.nan)
        full[:n] = u
        disp[name] = full
    return {d.name: evaluate(d.quantity, d.options, disp, d.levels, spec.levels) for d in spec.data}


def n_data(spec: FitSpec) -> int:
    return sum(len(d.levels) for d in spec.data)


QUANTITY_UNITS = {name: q.unit for name, q in QUANTITIES.items()}
#: a start whose model values differ from the data by more than this factor (median over a data
#: set's levels) gets a warning: a unit the data were not converted from, most likely
UNIT_HINT_FACTOR = 30.0


def start_ratios(spec: FitSpec, start: Sample) -> list[str]:
    """Lines for the log: per data set the median ratio model / data at the start, with a warning
    (and the unit hint) where it is off by more than ``UNIT_HINT_FACTOR``."""
    out = []
    for d in spec.data:
        model = np.asarray(start.model[d.name], dtype=float)
        ok = np.isfinite(model) & (d.values != 0.0)
        if not ok.any():
            continue
        ratio = float(np.median(model[ok] / d.values[ok]))
        line = f"{d.name}: model / data = {ratio:.3g} at the start (median over {int(ok.sum())} level(s))"
        if not 1.0 / UNIT_HINT_FACTOR <= abs(ratio) <= UNIT_HINT_FACTOR or ratio < 0:
            line = (f"warning: {line}; are the data in SI units ({d.quantity}: "
                    f"{QUANTITY_UNITS.get(d.quantity, 'm')}) and of the model's sign? value_scale "
                    f"converts the column {d.value_column!r} (1e-3 for mm; now {d.value_scale:g})")
        out.append(line)
    return out


def optimum_notes(spec: FitSpec, sample: Sample) -> list[str]:
    """Warnings on the fitted sample: that it failed (its levels not reached carry the penalty),
    and one per level of the data its model reached only past a gap of the load path (its
    values there are at the reported load factor, not at the level)."""
    out = []
    if not sample.ok:
        out.append(f"warning: the fitted sample is {sample.status} ({sample.reason_code}: {sample.message}); "
                   f"it reached {sample.levels_reached} of {len(spec.levels)} level(s), the others carry "
                   f"objective.penalty ({spec.penalty:g} sigma): the optimum is not a fit of the data")
    for level, at in sample.passed_over:
        names = ", ".join(d.name for d in spec.data if np.any(np.isclose(d.all_levels, level, rtol=1e-12, atol=0.0)))
        out.append(f"warning: level {level:g} ({names}) lies in a gap of the load path at these parameters: "
                   f"the model's values there are at load factor {at:.6g}, past the gap (solver.step_over_jumps; "
                   'docs/running.md, "Levels in a gap of the load path")')
    return out
