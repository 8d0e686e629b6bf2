"""Where the verification package reads and writes: the checkout's configs/, docs/ and scripts/,
and the summary a run wrote there."""
from __future__ import annotations

import json
import os
import subprocess

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CONFIGS = os.path.join(ROOT, "configs")
DOCS = os.path.join(ROOT, "docs")
SCRIPTS = os.path.join(ROOT, "scripts")


def run_summary(run_dir: str, proc: subprocess.CompletedProcess, name: str) -> dict:
    """``run_dir``/summary.json of the ``ancf-solve`` process ``proc``; a run that wrote none (a
    config error, a crash) stops the command ``name`` with one line: the run's last message."""
    path = os.path.join(run_dir, "summary.json")
    if not os.path.exists(path):
        last = ((proc.stderr or "") + (proc.stdout or "")).strip().splitlines()[-1:] or ["no output"]
        raise SystemExit(f"{name}: {run_dir}: ancf-solve wrote no summary.json (exit {proc.returncode}): "
                         f"{last[0]}")
    with open(path) as fh:
        return json.load(fh)
