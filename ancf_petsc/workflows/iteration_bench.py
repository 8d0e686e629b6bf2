"""The cost of the paper's tendon (issue 40): a Newton iteration, the column, start-up, the kernel
(``scripts/bench_iteration.py``, ``make bench-iteration``; docs/parallel.md).

Runs the ψ = 45° Table 1 column (configs/achilles_type3_psi45.yaml, 4 elements per subtendon,
sliding contact; 1 rank, ``--quiet``) and the element kernel of this checkout and of each
``--baseline NAME=DIR`` (another checkout with its own .venv, e.g. a ``git worktree`` of an older
commit), one run of each in turn per round (A B C, then C B A, ...), and prints per quantity the
median of every checkout and the median of the per-round ratios against each baseline (speed-up:
> 1 is faster), so that the comparison holds while the shared machine's speed drifts:

* Newton iteration [ms]: the column's solve time / its Newton iterations, measured in-process
  (summary.json ``timings.solve``: residuals, Jacobians, contact projection and pairing, linear
  solves, the stepper; not the output);
* column solve part [s] (``timings.solve``) and column wall [s] (the whole process);
* start-up [s]: from starting the process to the first residual evaluation (the first Newton
  iteration; a ``sitecustomize`` hook on PYTHONPATH notes the time, nothing else changes);
* kernel [M GP/s]: ``kernels.internal_force_and_tangent`` (residual + tangent) on 64 elements
  3363 of degree 6 × 3 axial points (84 per element: the paper's rule and section cubature),
  neo-Hookean and GOH (workflows/kernel_bench.py's ``block``: fibres along the pretwisted lines, all in
  tension); best of 20 calls.
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CONFIG = os.path.join("configs", "achilles_type3_psi45.yaml")     # each checkout's own
TARGETS = {"iteration_ms": ("<=", 3.0), "solve_s": ("<=", 0.15), "wall_s": ("<=", 0.5),
           "startup_s": ("<=", 0.3), "kernel_nh": (">=", 1.5), "kernel_goh": (">=", 1.5)}
LABELS = {"iteration_ms": "Newton iteration [ms]", "solve_s": "column solve part [s]",
          "wall_s": "column wall [s]", "startup_s": "start-up to 1st iteration [s]",
          "kernel_nh": "kernel neo-Hookean [M GP/s]", "kernel_goh": "kernel GOH [M GP/s]"}
RATES = ("kernel_nh", "kernel_goh")          # larger is faster

#: on PYTHONPATH as sitecustomize: the first residual evaluation writes time.time() to a file
HOOK = '''
import importlib.abc, importlib.util, os, sys, time
try:
    import apport_python_hook            # what Debian's own sitecustomize does
except ImportError:
    pass
else:
    apport_python_hook.install()
_OUT = os.environ.get("ANCF_BENCH_FIRST_RESIDUAL")

class _Finder(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path, target=None):
        if name != "ancf_petsc.petsc.problem" or not _OUT:
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(name)
        run = spec.loader.exec_module

        def exec_module(module):
            run(module)
            residual = module.Problem.residual

            def first(self, *args):
                if not os.path.exists(_OUT):
                    with open(_OUT, "w") as fh:
                        fh.write(repr(time.time()))
                return residual(self, *args)
            module.Problem.residual = first
        spec.loader.exec_module = exec_module
        return spec

sys.meta_path.insert(0, _Finder())
'''

#: run by each checkout's own python (argv[1]: this checkout's workflows/kernel_bench.py, whose
#: ``block`` it takes): the kernel rate of neo-Hookean and GOH, if that checkout has GOH
KERNEL = r'''
import ast, json, sys, time
import numpy as np
from ancf_petsc.physics import element3363 as el, kernels
from ancf_petsc.physics.cubature import gauss_legendre
from ancf_petsc.physics.geometry import reference_nodal_vectors
from ancf_petsc.physics.materials import NeoHookean
from ancf_petsc.physics.section import make_ellipse
try:
    from ancf_petsc.physics.fibres import fibre_directions
    from ancf_petsc.physics.goh import GOH
except ImportError:
    GOH = None
source = open(sys.argv[1]).read()
node = next(n for n in ast.parse(source).body if isinstance(n, ast.FunctionDef) and n.name == "block")
exec("from __future__ import annotations\n" + ast.get_source_segment(source, node))

def rate(fn, n, repeat=20):
    fn()
    best = np.inf
    for _ in range(repeat):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return n / best / 1e6

qe, G, w = block(64, 6, 3)
out = {"kernel_nh": rate(lambda: kernels.internal_force_and_tangent(qe, G, w, NeoHookean(1e6, 5e7)), w.size)}
if GOH is not None:
    qe, G, w, law = block(64, 6, 3, GOH(1e6, 5e7, 2e6, 5.0, 0.1))
    out["kernel_goh"] = rate(lambda: kernels.internal_force_and_tangent(qe, G, w, law), w.size)
print(json.dumps(out))
'''


def child_env() -> dict:
    env = dict(os.environ, OPENBLAS_NUM_THREADS="1", OMP_NUM_THREADS="1")
    env.pop("PYTHONPATH", None)
    return env


def run_column(tree: str, hook_dir: str, pin: str | None) -> dict:
    """One column of ``tree``: wall, solve part, per-iteration cost and start-up."""
    with tempfile.TemporaryDirectory(prefix="ancf-bench-") as out:
        mark = os.path.join(out, "first_residual")
        env = child_env()
        env.update(PYTHONPATH=hook_dir, ANCF_BENCH_FIRST_RESIDUAL=mark)
        cmd = [os.path.join(tree, ".venv", "bin", "ancf-solve"), os.path.join(tree, CONFIG), "--quiet",
               "--output-dir", os.path.join(out, "run")]
        if pin is not None:
            cmd = ["taskset", "-c", pin] + cmd
        t0 = time.time()
        p0 = time.perf_counter()
        proc = subprocess.run(cmd, env=env, cwd=tree, capture_output=True, text=True)
        wall = time.perf_counter() - p0
        if proc.returncode != 0:
            raise RuntimeError(f"{tree}: ancf-solve exited {proc.returncode}: {proc.stderr[-500:]}")
        with open(os.path.join(out, "run", "summary.json")) as fh:
            summary = json.load(fh)
        with open(mark) as fh:
            first = float(fh.read())
    solve = summary["timings"]["solve"]
    return {"wall_s": wall, "solve_s": solve, "startup_s": first - t0,
            "iteration_ms": 1e3 * solve / summary["newton_iterations"],
            "iterations": summary["newton_iterations"]}


def run_kernel(tree: str, pin: str | None) -> dict:
    cmd = [os.path.join(tree, ".venv", "bin", "python"), "-c", KERNEL,
           os.path.join(ROOT, "ancf_petsc", "workflows", "kernel_bench.py")]
    if pin is not None:
        cmd = ["taskset", "-c", pin] + cmd
    proc = subprocess.run(cmd, env=child_env(), cwd=tree, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{tree}: kernel benchmark failed: {proc.stderr[-500:]}")
    return json.loads(proc.stdout.strip().splitlines()[-1])


def fmt(q: str, v: float | None) -> str:
    if v is None:
        return "n/a"
    return f"{v:.2f}" if q in ("iteration_ms",) or q in RATES else f"{v:.3f}"


def main(argv: list[str] | None = None) -> int:
    """The command line: run the rounds, print the table (and --json every run's figures)."""
    ap = argparse.ArgumentParser(prog="bench_iteration.py", allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--baseline", action="append", default=[], metavar="NAME=DIR",
                    help="another checkout with its own .venv (make setup there)")
    ap.add_argument("--pin", default=None, help="CPU list for taskset (e.g. 1)")
    ap.add_argument("--json", help="also write every run's figures here")
    args = ap.parse_args(argv)
    trees = [("this", ROOT)] + [tuple(b.split("=", 1)) for b in args.baseline]
    runs = {name: [] for name, _ in trees}
    with tempfile.TemporaryDirectory(prefix="ancf-bench-hook-") as hook_dir:
        with open(os.path.join(hook_dir, "sitecustomize.py"), "w") as fh:
            fh.write(HOOK)
        for name, tree in trees:                      # warm-up: page cache, .pyc files
            run_column(tree, hook_dir, args.pin)
        for r in range(args.rounds):
            for name, tree in (trees if r % 2 == 0 else trees[::-1]):
                fig = run_column(tree, hook_dir, args.pin)
                fig.update(run_kernel(tree, args.pin))
                runs[name].append(fig)
            print(f"# round {r + 1}/{args.rounds} done", file=sys.stderr, flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(runs, fh, indent=1)
    print(f"# {os.path.basename(CONFIG)}, 1 rank, OPENBLAS_NUM_THREADS=1, {args.rounds} rounds "
          f"(checkouts in turn); medians, and the median of the per-round speed-ups (> 1: this is faster)")
    print("# Newton iterations: " + ", ".join(f"{n} {runs[n][0]['iterations']}" for n, _ in trees))
    head = f"{'quantity':32s} {'target':>8s} " + " ".join(f"{n:>10s}" for n, _ in trees)
    head += "".join(f"  {'speed-up vs ' + n:>24s}" for n, _ in trees[1:])
    print(head)
    for q in TARGETS:
        cols = []
        for name, _ in trees:
            vals = [f[q] for f in runs[name] if q in f]
            cols.append(statistics.median(vals) if vals else None)
        line = f"{LABELS[q]:32s} {TARGETS[q][0] + str(TARGETS[q][1]):>8s} " + " ".join(f"{fmt(q, v):>10s}" for v in cols)
        for name, _ in trees[1:]:
            pairs = [(a[q], b[q]) for a, b in zip(runs["this"], runs[name]) if q in a and q in b]
            if not pairs:
                line += f"  {'n/a':>24s}"
                continue
            ratios = sorted(a / b if q in RATES else b / a for a, b in pairs)
            line += f"  {statistics.median(ratios):6.2f}x ({ratios[0]:.2f}-{ratios[-1]:.2f})".rjust(26)
        print(line)

    return 0
