"""Parameter sweeps over a base config: expansion into run directories, local execution,
SLURM job-array scripts and collection into one CSV (no argument parsing; see apps/ancf_sweep.py).

Modules: ``spec`` (the sweep file), ``expand`` (runs and their directories), ``execute`` (one run as
a child process), ``runner`` (local parallel runs), ``collect`` (the CSV), ``slurm`` (job arrays),
``base`` (statuses, errors, key paths).

A sweep file (YAML)::

    base: configs/achilles_type3_psi45.yaml   # the model config, relative to the sweep file
    name: twist_sweep                         # default: the sweep file's stem
    mode: grid                                # grid (Cartesian product) | list (zip, equal lengths)
    parameters:                               # dotted key paths into the base config
      geometry.twist_deg: [0, 15, 45]
      beams[0].material.bulk_modulus: [0.5e9, 0.86e9]
    run: {ranks: 1, jobs: 2, petsc: ["-snes_rtol", "1e-9"], timeout: 3600, mpiexec: mpirun}
    output: sweeps/twist_sweep                # root directory, relative to the sweep file
    slurm:                                    # only for --slurm (all optional)
      throttle: 20                            # at most 20 array tasks at once (--array=0-N%20)
      cpus_per_task: 1
      mem: 4G                                 # per node, SLURM's syntax
      time: "02:00:00"                        # default: run.timeout plus 2 minutes, else none
      partition: short
      account: myproject
      venv: ../.venv                          # relative to the sweep file (or absolute)
      logs: append                            # append | numbered: log.txt on resubmission

Every run gets ``<output>/<run id>/`` with ``config.yaml`` (the base config with the values
substituted, ``output.dir`` set to the run directory and the base's relative data files, swept
ones included, made relative to the run directory where they share a tree), ``params.json`` and,
once run, ``log.txt``,
``run.json`` (status, reason, wall time),
plus the solver's own ``summary.json``, ``results.h5`` and VTU files.
"""
from .base import (DONE_STATUSES, FAILED_STATUSES, FINAL_STATUSES, STATUS_ORDER, SweepError, format_key_path,
                   parse_key_path, set_key_path)
from .collect import Collection, RunState, collect, run_state
from .execute import Outcome, classify, execute_run, finish_slurm_task
from .expand import check_values, config_text, expand, format_value, is_done, prepare_run, run_config
from .runner import SweepReport, run_sweep
from .slurm import write_slurm
from .spec import Parameter, RunSpec, Sweep, load_sweep, slurm_spec

__all__ = ["DONE_STATUSES", "FAILED_STATUSES", "FINAL_STATUSES", "STATUS_ORDER", "Collection", "Outcome",
           "Parameter", "RunSpec", "RunState", "Sweep", "SweepError", "SweepReport", "classify", "collect",
           "check_values", "config_text", "execute_run", "expand", "finish_slurm_task", "format_key_path", "format_value",
           "is_done", "load_sweep", "parse_key_path", "prepare_run", "run_config", "run_state", "run_sweep",
           "set_key_path", "slurm_spec", "write_slurm"]
