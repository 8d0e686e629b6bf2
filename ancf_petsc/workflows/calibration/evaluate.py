"""Residuals of parameter sets: from the log when a set was solved before, else solved in this
process (a ``SampleSolver`` per rank: the model built once, warm-started from the library), the
new sets of a batch spread over the MPI ranks and gathered, then logged."""
from __future__ import annotations

import numpy as np

from ...config.parse import parse_config
from ...errors import InputError
from ...solving.samples import SampleSolver
from ...solving.spread import spread, world
from ...status import CONFIG_ERROR
from .errors import CalibrationInterrupted
from .library import StateLibrary
from .log import SampleLog
from .parameters import from_u
from .sample import Sample, data_residuals, model_values, n_data
from .spec import FitSpec


class Evaluator:
    """``evaluator(U, phase)``: the samples of the parameter sets U (optimiser coordinates)."""

    def __init__(self, spec: FitSpec, log: SampleLog, say=lambda *_: None):
        self.spec, self.log, self.say = spec, log, say
        self.library = StateLibrary()
        self.solver: SampleSolver | None = None
        self.rank, self.size = world()
        self.asked = 0                          # parameter sets asked for (logged or not)

    def __call__(self, U: list, phase: str) -> list[Sample]:
        U = [np.asarray(u, dtype=float) for u in U]
        self.asked += len(U)
        todo, seen = [], set()
        for u in U:
            key = tuple(u)
            if self.log.get(u) is None and key not in seen:
                todo.append(u)
                seen.add(key)
        if todo:
            # every start is chosen before the batch: the same on every rank and rank count
            items = [(u, self.library.start_for(u)) for u in todo]
            done = spread(items, lambda item: self._solve(item, phase))
            new = [r for r in done.results if r is not None]
            self.log.add([s for s, _ in new])
            for s, states in new:
                if states is not None:
                    self.library.add(np.array(s.u), states)
            if done.signum:
                raise CalibrationInterrupted(done.signum)
        return [self.log.get(u) for u in U]

    def _solve(self, item, phase: str):
        """One parameter set on this rank: (its sample, its states for the library or None)."""
        u, (start, how) = item
        spec = self.spec
        values = from_u(spec.parameters, u)
        named = {p.name: float(v) for p, v in zip(spec.parameters, values)}
        base = dict(index=-1, phase=phase, u=[float(x) for x in u], parameters=named, rank=self.rank)
        try:
            mspec = parse_config(spec.config(values), base_dir=spec.model_dir)
            if self.solver is None:
                self.solver = SampleSolver()
            out = self.solver.solve(mspec, start)
        except InputError as exc:           # a value the model refuses (inside the bounds)
            return Sample(**base, status="config_error", reason_code=CONFIG_ERROR,
                          message=f"{exc.path}: {exc.message}", residuals=[spec.penalty] * n_data(spec),
                          model={d.name: [np.nan] * len(d.levels) for d in spec.data}), None
        model = model_values(spec, out)
        sample = Sample(**base, status=out.status, reason_code=out.reason_code, message=out.message,
                        residuals=data_residuals(spec, model).tolist(),
                        model={k: v.tolist() for k, v in model.items()}, inverted=out.inverted,
                        levels_reached=len(out.load_factors), newton_iterations=out.newton_iterations,
                        start=how if start is not None else "cold", warm_levels=out.warm_levels,
                        fallbacks=out.fallbacks, rebuilt=out.rebuilt, wall_time=out.wall_time,
                        cpu_time=out.cpu_time, passed_over=[[lv, at] for lv, _, at in out.passed_over])
        # a state reported past a gap of the load path is no start for its level (a warm solve
        # there may find the other side's equilibrium, which the sample's own path passes over)
        complete = out.status == "completed" and len(out.states) == len(spec.levels) and not out.passed_over
        return sample, (out.states if complete else None)

    def close(self) -> None:
        if self.solver is not None:
            self.solver.destroy()
            self.solver = None
