"""A multi-start fit (``optimizer.starts``) as a SLURM job array: task k runs start k
(``ancf-fit FIT --task k``, its own log in <output>/starts/k, resumed when resubmitted);
``ancf-fit FIT --collect`` then takes every start's samples into the main log, where the
multi-start fit replays them without solving, picks the best and analyses it.  The resources and
the environment come from the fit file's ``slurm:`` (the sweep's keys and rules)."""
from __future__ import annotations

import os
import shlex
import sys

from ...io.files import atomic_write
from ..sweep.slurm import default_venv
from .log import LOG_NAME, SampleLog
from .sample import Sample
from .spec import FitSpec


def write_slurm(spec: FitSpec, fit_file: str, ranks: int = 1) -> str:
    """``<output>/fit.slurm``: one array task per start; its path."""
    os.makedirs(spec.output, exist_ok=True)
    sl, q = spec.slurm, shlex.quote
    n = spec.optimizer.starts
    throttle = f"%{sl.throttle}" if sl.throttle is not None and sl.throttle < n else ""
    venv = sl.venv or default_venv()
    fit = q(os.path.abspath(fit_file))
    lines = ["#!/bin/bash", f"#SBATCH --job-name={spec.name}", f"#SBATCH --array=0-{n - 1}{throttle}",
             f"#SBATCH --ntasks={ranks}", "#SBATCH --output=slurm-%A_%a.out"]
    for option, value in (("time", sl.time), ("cpus-per-task", sl.cpus_per_task), ("mem", sl.mem),
                          ("partition", sl.partition), ("account", sl.account)):
        if value is not None:
            lines.append(f"#SBATCH --{option}={value}")
    exe = os.path.join(venv, "bin", "ancf-fit") if venv else os.path.join(os.path.dirname(sys.executable), "ancf-fit")
    lines += [f"# Calibration {spec.name}: {n} starts of a multi-start fit, one array task each.",
              f"# Submit:  cd {q(spec.output)} && sbatch fit.slurm",
              f"# Then:    ancf-fit {fit} --collect    (the best start, its errors, profiles, report)",
              "# A task stopped at its time limit goes on from its log when submitted again.",
              "set -u",
              'TASK="${SLURM_ARRAY_TASK_ID:?not running as a SLURM array task}"',
              f'ANCF_FIT="${{ANCF_VENV:+$ANCF_VENV/bin/ancf-fit}}"; ANCF_FIT="${{ANCF_FIT:-{exe}}}"',
              'export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"',
              'if command -v srun >/dev/null 2>&1; then LAUNCH=(srun --ntasks="${SLURM_NTASKS:-' + str(ranks) + '}")',
              f'else LAUNCH=(mpirun -n {ranks}); fi',
              f'"${{LAUNCH[@]}}" "$ANCF_FIT" {fit} --out {q(spec.output)} --task "$TASK"']
    script = os.path.join(spec.output, "fit.slurm")
    atomic_write(script, "\n".join(lines) + "\n")
    os.chmod(script, 0o755)
    return script


def merge_starts(spec: FitSpec) -> int:
    """Every start's logged samples into the main log (those it lacks); how many were added."""
    main = SampleLog(spec.output, spec)
    added, seen = [], set()
    root = os.path.join(spec.output, "starts")
    for k in range(spec.optimizer.starts):
        path = os.path.join(root, str(k))
        if os.path.exists(os.path.join(path, LOG_NAME)):
            for s in SampleLog(path, spec).samples:
                key = tuple(s.u)
                if main.get(s.u) is None and key not in seen:
                    seen.add(key)
                    added.append(Sample.from_record(s.record()))
    main.add(added)
    return len(added)
