"""A calibration from fit file to report: the fit (local, multi-start or global), the
uncertainty and profiles at its optimum, the verdicts, the files (collective over the ranks)."""
from __future__ import annotations

import os
import time
from dataclasses import dataclass, field

import numpy as np

from ...solving.spread import agree, world
from .errors import CalibrationError
from .evaluate import Evaluator
from .identify import (Profile, Uncertainty, at_bounds, interval, profile_width, relative_width,
                       uncertainty, verdict)
from .log import SampleLog
from .optimise import LocalFit, global_fit, local_fit, start_points
from .parameters import describe, from_u, to_u
from .profiles import profile
from .sample import Sample, optimum_notes, start_ratios
from .spec import FitSpec


@dataclass
class ParameterResult:
    name: str
    value: float
    se: float                        # standard error of p (first order)
    interval: tuple[float, float]    # linearised 95 % interval
    width: float                     # its relative half-width w
    verdict: str
    reason: str
    at_bound: bool
    start: float
    profile: Profile | None = None


@dataclass
class CalibrationResult:
    spec: FitSpec
    best: Sample
    fit: LocalFit
    uncertainty: Uncertainty | None
    parameters: list[ParameterResult]
    output: str
    wall_time: float
    throughput: dict = field(default_factory=dict)
    starts: list = field(default_factory=list)      # (start index, cost, status) of a multi-start


def open_log(directory: str, spec: FitSpec, fresh: bool) -> SampleLog:
    """The log on every rank: rank 0 reads (or starts) it, the others get its samples."""
    rank, _ = world()
    log, err = None, None
    if rank == 0:
        try:
            log = SampleLog(directory, spec, fresh)
        except CalibrationError as exc:
            err = (exc.path, exc.message)
    err = agree(err)
    if err:
        raise CalibrationError(*err)
    samples = agree(log.samples if rank == 0 else None)
    if rank != 0:
        log = SampleLog(directory, spec, fresh=True, writer=False)
        log.add(samples)
    log.resumed = len(samples)
    return log


def fit(ev: Evaluator, spec: FitSpec, task: int | None, say) -> tuple[LocalFit, list]:
    """The optimum: differential evolution (+ trf), or trf from each start (or start ``task``)."""
    if spec.optimizer.method == "differential_evolution":
        return global_fit(ev, spec, say), []
    starts = start_points(spec)
    chosen = range(len(starts)) if task is None else [task]
    fits = []
    for k in chosen:
        phase = "fit" if len(starts) == 1 else f"start:{k}"
        f = local_fit(ev, spec, starts[k], phase)
        say(f"[fit] {phase}: {describe(spec.parameters, from_u(spec.parameters, f.u))}; "
            f"cost {f.best.cost:.6g} ({f.status}, {f.samples} samples)")
        fits.append((k, f))
    best = min(fits, key=lambda kf: kf[1].best.cost)[1]
    return best, [(k, f.best.cost, f.status) for k, f in fits]


def analyse(ev: Evaluator, spec: FitSpec, result: LocalFit, say) -> tuple[Uncertainty | None, list]:
    """Standard errors, correlations, profiles and verdicts at the optimum."""
    params = spec.parameters
    u = result.u
    values = from_u(params, u)
    unc = uncertainty(result.jac, result.best.r, spec.absolute_sigma) if result.jac is not None else None
    bounds = at_bounds(params, u)
    out = []
    for i, par in enumerate(params):
        se_u = unc.se_u[i] if unc is not None else np.inf
        prof = None
        if spec.identifiability.profiles and unc is not None:
            prof = profile(ev, spec, u, 2.0 * result.best.cost, unc.s2, i, se_u, say)
        t95 = unc.t95 if unc is not None else np.inf
        w = relative_width(par, values[i], se_u, t95) if prof is None else profile_width(par, values[i], prof)
        v, why = verdict(w, prof)
        out.append(ParameterResult(par.name, float(values[i]), float(abs(par.dp_du(values[i])) * se_u),
                                   interval(par, u[i], se_u, t95), float(w), v, why, bounds[i],
                                   par.start, prof))
    return unc, out


def run_calibration(spec: FitSpec, fresh: bool = False, task: int | None = None,
                    say=print, write=None) -> CalibrationResult:
    """Fit, analyse and (through ``write``, on rank 0) report; resumes from the output's log."""
    t0 = time.perf_counter()
    output = spec.output if task is None else os.path.join(spec.output, "starts", str(task))
    log = open_log(output, spec, fresh)
    if log.resumed:
        say(f"[fit] resuming: {log.resumed} sample(s) read from {log.path}")
    ev = Evaluator(spec, log, say)
    try:
        start = ev([to_u(spec.parameters, [p.start for p in spec.parameters])], "fit")[0]
        for line in start_ratios(spec, start):
            say(f"[fit] {line}")
        best, starts = fit(ev, spec, task, say)
        for line in optimum_notes(spec, best.best):
            say(f"[fit] {line}")
        unc, params = analyse(ev, spec, best, say) if task is None else (None, [])
    finally:
        ev.close()
    result = CalibrationResult(spec, best.best, best, unc, params, output,
                               time.perf_counter() - t0, log.throughput(), starts)
    if write is not None and world()[0] == 0:
        write(result, log)
    return result
