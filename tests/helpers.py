"""Shared test helpers: run configs in-process (serial) or through ancf-solve under mpirun."""
from __future__ import annotations

import copy
import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CONFIGS = os.path.join(ROOT, "configs")
VENV_BIN = os.path.join(ROOT, ".venv", "bin")
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1", "OPENBLAS_NUM_THREADS": "1",
           "OMP_NUM_THREADS": "1"}


def load_raw(name: str) -> dict:
    with open(os.path.join(CONFIGS, name)) as fh:
        return yaml.safe_load(fh)


def cantilever(steps, elements: int = 4) -> dict:
    """configs/bending_neohookean.yaml (the clamped cantilever) at ``elements`` elements and
    ``steps``, without ParaView files."""
    raw = load_raw("bending_neohookean.yaml")
    raw["beams"][0]["elements"] = elements
    raw["steps"] = steps
    raw["output"] = {"vtk": False}
    return raw


def petsc_init():
    from mpi4py import MPI  # noqa: F401
    import petsc4py
    petsc4py.init([])


def fail_solves(when, put=setattr, lost: bool = False) -> None:
    """Every SNES solve for which ``when(solver, lam)`` holds fails with DIVERGED_FNORM_NAN (as a
    projection lost, marked so with ``lost``), without a Newton iteration; the others run.  ``put``:
    a monkeypatch's setattr, or setattr in a driver process (tests/parallel/test_mpi.py)."""
    petsc_init()
    from petsc4py import PETSc
    from ancf_petsc.solving.snes_solver import SNESSolver
    solve = SNESSolver.solve

    def failing(self, X, target, lam, reached):
        if when(self, lam):
            self.problem.contact_failed |= lost
            return PETSc.SNES.ConvergedReason.DIVERGED_FNORM_NAN, 0
        return solve(self, X, target, lam, reached)
    put(SNESSolver, "solve", failing)


def run_inline(raw: dict, out_dir: str, base_dir: str = CONFIGS, petsc: dict | None = None):
    """Run a raw config dict in this process (1 rank); returns the summary dict."""
    petsc_init()
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.api import solve
    raw = copy.deepcopy(raw)
    raw.setdefault("output", {})["dir"] = str(out_dir)
    if petsc:
        raw.setdefault("petsc", {}).update(petsc)
    spec = parse_config(raw, base_dir=base_dir)
    res = solve(spec, log=lambda *_: None)
    return res.summary


def bar_twin_fit(out_dir) -> dict:
    """configs/fits/bar_twin.yaml with its model and data files absolute and its output in
    ``out_dir`` (an ancf-fit input to write anywhere)."""
    import yaml
    with open(os.path.join(CONFIGS, "fits", "bar_twin.yaml")) as fh:
        fit = yaml.safe_load(fh)
    fit["model"] = os.path.join(CONFIGS, "calibration_bar.yaml")
    for d in fit["data"]:
        d["file"] = os.path.join(CONFIGS, "data", os.path.basename(d["file"]))
    fit["output"] = str(out_dir)
    return fit


def write_config(raw: dict, path) -> str:
    with open(path, "w") as fh:
        yaml.safe_dump(raw, fh, sort_keys=False)
    return str(path)


#: a test's ``ranks`` parameter on one rank and, marked ``mpi``, on two (make test runs the
#: marked tests one at a time: tests/conftest.py)
ONE_AND_TWO_RANKS = [1, pytest.param(2, marks=pytest.mark.mpi)]


def mpirun_ranks(cmd) -> int:
    """The rank count of an mpirun/mpiexec command line (a list); 1 for any other command."""
    if isinstance(cmd, (str, bytes)) or not cmd or \
            os.path.basename(str(cmd[0])) not in ("mpirun", "mpiexec"):
        return 1
    args = [str(a) for a in cmd]
    for flag in ("-n", "-np"):
        if flag in args:
            return int(args[args.index(flag) + 1])
    return 2                                  # no count given: every slot of the machine


def solve_cli(config_path: str, ranks: int = 1, extra: list | None = None, cwd: str | None = None,
              timeout: float = 600) -> subprocess.CompletedProcess:
    """Run ancf-solve (under mpirun when ranks > 1); returns the completed process."""
    exe = os.path.join(VENV_BIN, "ancf-solve")
    if not os.path.exists(exe):
        exe = None
    cmd = [exe] if exe else [sys.executable, "-m", "apps.ancf_solve"]
    cmd += [config_path] + (extra or [])
    if ranks > 1:
        cmd = ["mpirun", "--oversubscribe", "-n", str(ranks)] + cmd
    env = dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT)
    return subprocess.run(cmd, capture_output=True, text=True, cwd=cwd or ROOT, env=env,
                          timeout=timeout)


def solved_config(tmp_path_factory, name: str, timeout: float = 300):
    """configs/<name> solved by ancf-solve into a fresh temporary directory (module fixtures)."""
    out = tmp_path_factory.mktemp(os.path.splitext(name)[0])
    proc = solve_cli(os.path.join(CONFIGS, name), extra=["--output-dir", str(out), "--quiet"],
                     timeout=timeout)
    assert proc.returncode == 0, proc.stderr
    return out


def paper_column(name: str = "achilles_type3_psi45.yaml") -> dict:
    """A shipped tendon config whose sections file is named by its absolute path (the config is
    written elsewhere, e.g. under tmp_path)."""
    raw = load_raw(name)
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    return raw


def solved_run(raw: dict, tmp_path, name: str = "run", returncode: int = 0) -> str:
    """``raw`` written to tmp_path/<name>.yaml and solved by ancf-solve into tmp_path/<name>
    (quiet), its exit code checked; the run directory."""
    run = str(tmp_path / name)
    p = solve_cli(write_config(raw, tmp_path / f"{name}.yaml"), extra=["--output-dir", run, "--quiet"])
    assert p.returncode == returncode, p.stderr
    return run


def report_existing(runs, out) -> str:
    """``ancf-report --existing RUNS --out OUT`` (exit 0 checked): the report.md it wrote."""
    p = subprocess.run([os.path.join(VENV_BIN, "ancf-report"), "--existing", *runs, "--out", str(out)],
                       capture_output=True, text=True, cwd=ROOT, env=dict(os.environ, **MPI_ENV), timeout=300)
    assert p.returncode == 0, p.stderr
    with open(os.path.join(out, "report.md")) as fh:
        return fh.read()


def read_summary(out_dir) -> dict:
    with open(os.path.join(out_dir, "summary.json")) as fh:
        return json.load(fh)


def probe(summary: dict, name: str, step: int = -1, key: str = "displacement"):
    return summary["steps"][step]["probes"][name][key]


def build_problem(raw, matrix_type: str = "aij", partition: str = "blocks"):
    """A Problem of a raw config on PETSc.COMM_WORLD (1 rank under pytest; scripts run by mpirun
    get every rank), and the PETSc module."""
    petsc_init()
    from petsc4py import PETSc
    from ancf_petsc.petsc.problem import Problem
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.parallel.partition import make_layout
    from ancf_petsc.model.build import build_model
    from helpers import CONFIGS
    spec = parse_config(raw, base_dir=CONFIGS)
    model = build_model(spec)
    contact = None
    if spec.contact is not None:
        from ancf_petsc.contact import build_contact
        contact = build_contact(model, spec.contact, lambda *_: None)
    comm = PETSc.COMM_WORLD
    layout = make_layout(model, partition, comm.size, comm.rank, contact, comm.tompi4py())
    return Problem(model, layout, comm, contact, matrix_type), PETSc


def hex7_problem(loaded: bool, matrix: str = "sbaij", partition: str = "blocks", element: str | None = None):
    """bundle_hex7 on PETSc.COMM_WORLD, Jacobian at q0 of the first load level (no multipliers:
    no contact curvature) or after one Newton step with MUMPS (multipliers non-zero); returns
    (Problem, PETSc, the residual F).  ``element``: the bundle's element (default its own)."""
    raw = load_raw("bundle_hex7.yaml")
    if element is not None:
        raw["bundle"]["element"] = element
    raw["output"] = {"dir": "unused", "vtk": False}
    P, PETSc = build_problem(raw, matrix, partition)
    P.load_factor = 0.5
    X, F = P.q0.copy(), P.F.duplicate()
    P.residual(None, X, F)
    P.jacobian(None, X, P.J, P.J)
    if loaded:
        ksp = PETSc.KSP().create()
        ksp.setOperators(P.J)
        ksp.setType("preonly")
        ksp.getPC().setType("cholesky")
        ksp.getPC().setFactorSolverType("mumps")
        dx = X.duplicate()
        ksp.solve(F, dx)
        X.axpy(-1.0, dx)
        P.residual(None, X, F)
        P.jacobian(None, X, P.J, P.J)
        ksp.destroy()
    return P, PETSc, F


def apply_fascicle_schur(P, PETSc, F):
    """The fascicle Schur preconditioner (linalg/fieldsplit.py) set up on P.J and applied to F:
    (its context, the PC, the result y)."""
    from ancf_petsc.linalg.fascicles import fascicle_split
    from ancf_petsc.linalg.fieldsplit import FascicleSchur
    ctx = FascicleSchur(fascicle_split(P), PETSc.COMM_WORLD)
    pc = PETSc.PC().create()
    pc.setOperators(P.J, P.J)
    pc.setType(PETSc.PC.Type.PYTHON)
    pc.setPythonContext(ctx)
    pc.setUp()
    y = F.duplicate()
    pc.apply(F, y)
    return ctx, pc, y


def beam_of_dofs(P) -> np.ndarray:
    """The beam of every PETSc DOF of ``P`` (−1: a multiplier node)."""
    owner = np.full(P.n_blocks, -1)
    owner[P.layout.perm[:P.model.n_nodes]] = P.model.node_beam()
    return np.repeat(owner, P.model.dofs_per_node)


def without_cross_fascicle_blocks(J: np.ndarray, beam_of: np.ndarray) -> np.ndarray:
    """J_bd: J without the blocks that couple two different beams directly."""
    cross = (beam_of[:, None] >= 0) & (beam_of[None, :] >= 0) & (beam_of[:, None] != beam_of[None, :])
    return np.where(cross, 0.0, J)


def two_beam_twisted():
    """configs/pretwisted_bar.yaml with a second, clamped SVK beam beside it."""
    raw = load_raw("pretwisted_bar.yaml")
    raw["beams"].append({"name": "second", "section": {"shape": "outline", "curves": [
        {"points": [[-0.002, -0.004], [-0.001, -0.008], [-0.006, -0.007]]},
        {"points": [[-0.006, -0.007], [-0.007, -0.003], [-0.002, -0.004]]}]},
        "material": {"model": "svk", "E": 3.0e6, "nu": 0.3}, "elements": 3})
    raw["boundary_conditions"].append({"beam": "second", "node": "first", "fix": "clamped"})
    return raw


def probes_table(summary):
    """Every probe's displacement at every step, as one array (steps × probes, 3)."""
    rows = []
    for step in summary["steps"]:
        for name in sorted(step["probes"]):
            rows.append(step["probes"][name]["displacement"])
    return np.array(rows)


def run_on_ranks(raw: dict, tmp_path, ranks=(1, 2, 3)) -> dict:
    """``raw`` solved by ancf-solve on each rank count (output in n<ranks>, VTK on 2 ranks only):
    {n: (process, summary)}, each run completed on n ranks."""
    runs = {}
    for n in ranks:
        raw["output"] = {"dir": str(tmp_path / f"n{n}"), "vtk": n == 2}
        p = solve_cli(write_config(raw, tmp_path / f"c{n}.yaml"), ranks=n)
        assert p.returncode == 0, p.stdout + p.stderr
        s = read_summary(tmp_path / f"n{n}")
        assert s["status"] == "completed" and s["ranks"] == n
        runs[n] = (p, s)
    return runs


def assert_same_as_serial(tables: dict, rtol: float = 1e-9) -> None:
    """Every rank count's probe table (``probes_table``) equals the serial one, tables[1], to
    ``rtol`` of its largest entry."""
    scale = np.abs(tables[1]).max()
    for n, table in tables.items():
        assert table.shape == tables[1].shape, n
        err = np.abs(table - tables[1]).max() / scale
        assert err <= rtol, (n, err)


def perturbed_state(P, rng, amplitude: float):
    """P's state vector X set to q0 plus ``amplitude`` × N(0, 1) on the free DOFs; (X, free)."""
    X = P.X
    P.q0.copy(X)
    free = ~P.fixed_mask
    X.setArray(X.getArray() + amplitude * rng.standard_normal(X.getLocalSize()) * free)
    return X, free


#: the solver's one-line failure message (solver.LoadStepFailure), checked by tests as users read it
FAILURE_MESSAGE = re.compile(r"^could not reach load factor \S+: SNES failed at load factor \S+ "
                             r"\(last converged \S+\) with [A-Z_]+"
                             r"( after \d+ Newton iterations \(solver.max_newton_iterations = \d+"
                             r"(; \d+ of them before --restart)?\))?"
                             r"( \(an element was inverted, J <= 0\))?"
                             r"( \(Newton( converges only linearly|'s iterates wander)[^()]*\))?$")


def _paper_inputs():
    from ancf_petsc.paper import PaperInputs
    return PaperInputs(CONFIGS)


#: the reproduction's inputs in this checkout
PAPER_INPUTS = _paper_inputs()


def jacobian_and_difference(P, X, v, h: float = 1e-7):
    """(J v, central difference (F(X + h v) − F(X − h v)) / 2h, X + h v, X − h v) for a Problem
    whose Jacobian was assembled at X."""
    Jv, Fp, Fm, Xp, Xm = X.duplicate(), X.duplicate(), X.duplicate(), X.copy(), X.copy()
    P.J.mult(v, Jv)
    Xp.axpy(h, v)
    Xm.axpy(-h, v)
    P.residual(None, Xp, Fp)
    P.residual(None, Xm, Fm)
    return Jv.getArray().copy(), (Fp.getArray() - Fm.getArray()) / (2 * h), Xp, Xm


def contact_evaluation(P, X):
    """The contact's evaluation at X, the law free to change the status (``Contact.evaluate``)."""
    P.contact.allow_update = True
    return P.contact.evaluate(P.exchange.local_state(X).copy(), P.exchange.needed)


def press_where_penetrating(P, X, st) -> None:
    """A state a unilateral law keeps (one rank): the multipliers pressing where the bodies
    penetrate at the evaluation ``st``, their random pulls elsewhere, every status active."""
    c = P.contact
    assert len(P.exchange.needed) == P.n_blocks        # one rank: local positions are global ones
    x = X.getArray()
    pos = c.multiplier_positions(P.exchange.needed)
    x[pos] = np.where(st.gbar < 0, np.abs(st.z), st.z)
    X.setArray(x)
    c.status[:] = True


def assert_contact_jacobian(P, X, free, act, h: float, samples: int = 3):
    """J (assembled here at X) times random free directions against central differences of F
    (1e-6 of max |J v|), the active set ``act`` unchanged within each probe; J as a dense array."""
    from petsc4py import PETSc
    P.jacobian(None, X, P.J, P.J)
    rng = np.random.default_rng(7)
    for _ in range(samples):
        v = X.duplicate()
        v.setArray(rng.standard_normal(X.getLocalSize()) * free * 1e-3)
        jv, fd, Xp, Xm = jacobian_and_difference(P, X, v, h)
        for Y in (Xp, Xm):
            assert np.array_equal(contact_evaluation(P, Y).active, act)
        err = np.abs(jv - fd)[free].max() / np.abs(jv).max()
        assert err < 1e-6, err
    return P.J.convert("dense", PETSc.Mat()).getDenseArray()

def assert_jacobian_and_gradient(P, X, free, rng, gradient_rel: float, samples: int = 2, h: float = 1e-7):
    """For a Problem whose Jacobian was assembled at X: J v against central differences of the
    residual (1e-6 of max |J v| on the free DOFs) and the residual against the central difference
    of the objective (the line-search merit) to ``gradient_rel``, for ``samples`` random free v."""
    for _ in range(samples):
        v = X.duplicate()
        v.setArray(rng.standard_normal(X.getLocalSize()) * free)
        jv, fd, Xp, Xm = jacobian_and_difference(P, X, v, h)
        assert np.abs(jv - fd)[free].max() <= 1e-6 * np.abs(jv).max()
        dE = (P.objective(None, Xp) - P.objective(None, Xm)) / (2 * h)
        F = X.duplicate()
        P.residual(None, X, F)
        assert dE == pytest.approx(F.dot(v), rel=gradient_rel)


def subject2_stride_frames(twist: float, bias: str, stop: int) -> dict:
    """Frames 1 … ``stop`` of the shipped walking stride of ``bias`` (its CSV's rows, as the
    envelope's strides read them) on the traced second subject at ``twist`` degrees, unilateral
    contact, 4 elements."""
    from ancf_petsc.workflows.envelope import DATA, STRIDE_COLUMNS, SUBJECT2, EnvelopeCell, cell_config
    with open(os.path.join(DATA, f"stride_walking_{bias}.csv")) as fh:
        lines = [line.strip().split(",") for line in fh if not line.startswith("#")]
    columns = dict(zip(lines[0], zip(*[[float(v) for v in row] for row in lines[1:stop + 1]])))
    raw = cell_config(EnvelopeCell(SUBJECT2, twist, bias, "unilateral", stride=True))
    raw["history"] = {"table": {c: list(columns[c]) for c in ("time",) + STRIDE_COLUMNS}}
    return raw


def unilateral_stride_frames(first: int = 4, stop: int = 22) -> dict:
    """Frames first+1 … stop of the shipped walking stride (uniform bias) at ψ = 45°, unilateral
    contact, as a history of their own: loading frames whose active set settles."""
    from ancf_petsc.workflows.envelope import NEO, EnvelopeCell, cell_config
    from ancf_petsc.workflows.stride import OPENSIM_COLUMNS, synthetic_stride
    times, forces = synthetic_stride("uniform")
    raw = cell_config(EnvelopeCell(NEO, 45, "uniform", "unilateral", stride=True))
    sel = slice(first, stop)
    raw["history"] = {"table": {"time": times[sel].tolist(), **{c: forces[c][sel].tolist() for c in OPENSIM_COLUMNS}}}
    raw["output"] = {"vtk": False}
    return raw


def bundle_owners() -> dict:
    """Element owners of bundle_hex37 (2 elements per fascicle) from METIS: whole beams on 2, 3
    and 4 ranks, the element graph on 2 and 3 (parallel/partition.py)."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.contact import build_contact
    from ancf_petsc.model.build import build_model
    from ancf_petsc.parallel.partition import beam_owner, metis_owner
    raw = load_raw("bundle_hex37.yaml")
    raw["bundle"]["elements"] = 2
    spec = parse_config(raw, base_dir=CONFIGS)
    model = build_model(spec)
    contact = build_contact(model, spec.contact, lambda *a: None)
    return {"beams": [beam_owner(model, n, contact).tolist() for n in (2, 3, 4)],
            "metis": [metis_owner(model, n, contact).tolist() for n in (2, 3)]}
