"""The GOH parameter sets of the paper's authors' public code in this model (issue 26): why the
full published set failed, and which sets converge.

Measures, on the soleus of configs/achilles_type3_psi45_goh.yaml (alone: no contact, ``fix:
reduced``) and on the whole ψ = 45° column:

1. ``reference``: Ē at the Gauss points of the unloaded soleus (it is ±1e-15: F = I to rounding)
   and the first Newton step from rest at 1 N with the published matrix, with the switch's
   tangent taken at Ē >= -E_ROUNDING (today) and at Ē >= 0 exactly (before: ``E_ROUNDING = 0``).
2. ``bulk``: the lone soleus with the published μ, k1, k2 through Table 1's 13 levels for
   K/μ = 3268 (the source's penalty 1e8 (J − 1)²), 49.67 (ν = 0.49) and 8.34 (the paper's
   Achilles ratio), 2 and 3 axial Gauss points, 4 and 8 elements; where each stops.
3. ``eigen``: the lowest eigenvalue of the Jacobi-scaled tangent D^-1/2 K D^-1/2 (free DOFs)
   along the load path, K/μ = 3268 against 49.67.
4. ``sets``: every set of the authors' code with K = 49.67 μ: the lone soleus (3 axial points)
   and the column with sliding and with unilateral contact (4 elements).
5. ``fade``: the columns that met the fade weights (``FADE_RUNS``) with ``contact.fade: newton``
   (``fade set:mode ...``: chosen ones).
6. ``fold``: the lone soleus with solver_default_2025 along a continuous path from rest
   (increments of at most 1 N): the lowest scaled tangent eigenvalue as the path nears its limit
   point, and the same soleus with the default increments (its first level lands on another
   stable branch).
7. ``column_fold``: the solver_default_2025 column (unilateral, fade newton) through levels up to
   89.5 N: at every converged level the smallest singular values of the Jacobi-scaled Jacobian,
   the lowest scaled eigenvalue of the soleus' own block and the fibre strain Ē (min, max) per
   soleus element; then the lone soleus with its end's r_x prescribed (displacement control)
   through its fold, with the end's reaction.
8. ``column_limit``: the same column to 90.711 N, then Newton by hand (LU, active set kept) at
   loads nearing its stop (90.7114 N): the smallest scaled singular values (∝ √(λc − λ) at a
   limit point) and the gastrocnemii's ends.
9. ``traction``: every set's lone soleus and column (unilateral, fade newton) with the load spread
   over the soleus' end section (``traction_force``) against the paper's point force on r; the
   fibre strain Ē (min, max) at 10 N under both; with the traction both contact laws and fade
   modes at 4 elements, and unilateral contact at 8.
"""
from __future__ import annotations

import copy
import json
import os
import sys

from ancf_verify import paths

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
ROOT = paths.ROOT

import numpy as np  # noqa: E402

from ancf_verify.studies.goh_sets import (CONFIGS, LEVELS, NU49, PUBLISHED, SETS, column,  # noqa: E402,F401
                                          published_law, solve)


def _run(raw: dict, e_rounding: float | None = None):
    """A Run (model, problem) of ``raw`` without solving; ``e_rounding``: the GOH laws' switch
    tolerance (None: the default, physics/goh.py E_ROUNDING)."""
    from petsc4py import PETSc
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import Run
    spec = parse_config(copy.deepcopy(raw), base_dir=CONFIGS)
    if e_rounding is not None:
        for b in spec.beams:
            b.material["e_rounding"] = e_rounding
    return Run(spec, PETSc.COMM_WORLD, lambda *_: None)


def part_strains(blk, xl, G, mat) -> np.ndarray:
    """Ē (not clipped) of the first fibre family at the Gauss points of one part of a block
    (elements first) at the local state xl."""
    from ancf_petsc.physics import kernels
    F = kernels.deformation_gradient(blk.element_vectors(xl), G)
    Fa = np.einsum("...ij,...j->...i", F, mat.a0[0])
    return np.einsum("...i,...i->...", Fa, Fa) - 1.0


def fibre_strains(problem, X) -> np.ndarray:
    """Ē (not clipped) at every Gauss point of the fibre-reinforced parts at state X."""
    xl = problem.exchange.local_state(X)
    return np.concatenate([part_strains(blk, xl, G, mat).ravel()
                           for blk in problem.blocks for G, _, mat in blk.parts])


def first_step(raw: dict, load: float, e_rounding: float | None = None) -> dict:
    """One full Newton step from rest at ``load`` [N]: the end node's move and what follows."""
    from petsc4py import PETSc
    run = _run(raw, e_rounding)
    try:
        pb = run.problem
        X, F = pb.q0.copy(), pb.F.duplicate()
        pb.load_factor = load
        pb.residual(None, X, F)
        pb.jacobian(None, X, pb.J, pb.J)
        ksp = PETSc.KSP().create()
        ksp.setOperators(pb.J)
        ksp.setType("preonly")
        ksp.getPC().setType("cholesky")
        ksp.getPC().setFactorSolverType("mumps")
        dX = X.duplicate()
        ksp.solve(F, dX)
        X.axpy(-1.0, dX)
        F1 = F.duplicate()
        pb.residual(None, X, F1)
        move = -dX.getArray().reshape(-1, 6, 3)[-1, 0]
        out = {"rest_E": fibre_strains(pb, pb.q0), "move_mm": 1e3 * move, "residual": F1.norm(),
               "max_E": float(np.nanmax(fibre_strains(pb, X)))}
        ksp.destroy()
        return out
    finally:
        run.destroy()


def reference() -> None:
    from ancf_petsc.physics import goh
    raw = column(**PUBLISHED, mode=None, axial_points=2)
    for psi in (0, 45):
        r = dict(raw, geometry=dict(raw["geometry"], twist_deg=psi))
        for tol, when in ((goh.E_ROUNDING, "today"), (0.0, "before")):
            s = first_step(r, 1.0, tol)
            E = s["rest_E"]
            print(f"psi {psi}: unloaded soleus, Ē in [{E.min():.2e}, {E.max():.2e}], {100 * (E < 0).mean():.1f} % "
                  f"of the points below 0; switch {when} (tangent on at Ē >= -{tol:g}): first Newton step "
                  f"at 1 N moves the end node by {np.array2string(s['move_mm'], precision=3)} mm, then "
                  f"|F| = {s['residual']:.3g} N, max Ē {s['max_E']:.3g}", flush=True)


def bulk() -> None:
    base = {k: PUBLISHED[k] for k in ("mu", "k1", "k2")}
    for ratio in (PUBLISHED["K"] / PUBLISHED["mu"], NU49, 8.34):
        for ap, ne in ((2, 4), (3, 4), (3, 8), (2, 8)):
            s = solve(column(**base, K=ratio * PUBLISHED["mu"], mode=None, elements=ne, axial_points=ap))
            print(f"lone soleus K/mu {ratio:.4g}, {ne} el., {ap} axial points: {s['status']}, last level "
                  f"{s['last']:g} N ({s['levels']}/13), {s['cutbacks']} cut-backs, {s['newton']} Newton, "
                  f"{s['wall']:.1f} s {s['message'][:95] if s['status'] != 'completed' else ''}", flush=True)


def lowest_scaled_eigenvalues(raw: dict, out_dir: str) -> list[tuple[float, float]]:
    """(level, lowest eigenvalue of D^-1/2 K D^-1/2 on the free DOFs) at every converged level."""
    import h5py
    run = _run(raw)
    try:
        pb = run.problem
        free = np.setdiff1d(np.arange(pb.model.n_dofs), pb.model.fixed_dofs)
        out = []
        with h5py.File(os.path.join(out_dir, "results.h5"), "r") as h5:
            for k in range(1, int(h5["steps"].attrs["converged"]) + 1):
                X = pb.q0.duplicate()
                X.setArray(h5[f"steps/step_{k:04d}/nodal_vectors"][:].ravel())
                pb.jacobian(None, X, pb.J, pb.J)
                M = pb.J.copy()
                M.convert("seqaij")
                A = M.convert("dense").getDenseArray()
                A = np.triu(A) + np.triu(A, 1).T if np.allclose(np.tril(A, -1), 0.0) else 0.5 * (A + A.T)
                A = A[np.ix_(free, free)]
                d = 1.0 / np.sqrt(np.abs(np.diag(A)))
                out.append((raw["steps"][k - 1], float(np.linalg.eigvalsh(d[:, None] * A * d[None, :])[0])))
        return out
    finally:
        run.destroy()


def eigen() -> None:
    steps = [1, 2, 5, 8, 9, 9.3, 9.4, 9.45, 9.47]
    for ratio in (PUBLISHED["K"] / PUBLISHED["mu"], NU49):
        raw = column(**dict(PUBLISHED, K=ratio * PUBLISHED["mu"]), mode=None, axial_points=2, steps=steps)
        s = solve(raw)
        ev = lowest_scaled_eigenvalues(raw, s["dir"])
        print(f"lone soleus K/mu {ratio:.4g}, 4 el., 2 axial points ({s['status']}): lowest scaled eigenvalue "
              + ", ".join(f"{lv:g} N: {v:.2e}" for lv, v in ev), flush=True)


def sets() -> None:
    for name in SETS:
        law = published_law(name)
        for mode in (None, "sliding", "unilateral"):
            s = solve(column(**law, mode=mode))
            print(f"{name}: {mode or 'lone soleus'}: {s['status']}, last level {s['last']:g} N "
                  f"({s['levels']}/13), {s['cutbacks']} cut-backs, {s['newton']} Newton, soleus "
                  f"{s['soleus_mm']:.3f} mm, {s['wall']:.1f} s {s['message'][:110] if s['status'] != 'completed' else ''}",
                  flush=True)


#: the columns whose runs met the fade weights (docs/fibres.md "Which sets run")
FADE_RUNS = [("tendon_model_2023", "unilateral"), ("alex", "unilateral"),
             ("solver_default_2025", "unilateral"), ("tendon_model_2023", "sliding"),
             ("alex", "sliding"), ("optimized_SEE", "sliding"), ("solver_default_2025", "sliding")]


def fade(runs=None) -> None:
    """The columns of ``FADE_RUNS`` (or ``runs``: "set:mode" words) with ``contact.fade:
    newton`` (the fade weights differentiated in Newton's iteration, contact/weights.py)."""
    chosen = [tuple(r.split(":")) for r in runs] if runs else FADE_RUNS
    for name, mode in chosen:
        raw = column(**published_law(name), mode=mode)
        raw["contact"]["fade"] = "newton"
        s = solve(raw)
        print(f"{name}: {mode}, fade newton: {s['status']}, last level {s['last']:g} N ({s['levels']}/13), "
              f"{s['cutbacks']} cut-backs, {s['newton']} Newton, soleus {s['soleus_mm']:.5f} mm, "
              f"{s['wall']:.1f} s {s['message'][:110] if s['status'] != 'completed' else ''}", flush=True)


def fold() -> None:
    law = published_law("solver_default_2025")
    steps = LEVELS[:8] + [95, 99, 99.4, 99.49, 99.5, 99.501, 100]
    raw = column(**law, mode=None, steps=steps)
    raw["solver"] = {"max_increment": 1.0, "initial_increment": 1.0}
    s = solve(raw)
    print(f"solver_default_2025, lone soleus, increments <= 1 N: {s['status']}, last level {s['last']:g} N, "
          f"{s['newton']} Newton {s['message'][:100] if s['status'] != 'completed' else ''}", flush=True)
    ev = lowest_scaled_eigenvalues(raw, s["dir"])
    print("  lowest scaled eigenvalue: " + ", ".join(f"{lv:g} N: {v:.2e}" for lv, v in ev[7:]), flush=True)
    for name, r in (("increments <= 1 N", raw), ("default increments", column(**law, mode=None))):
        r = copy.deepcopy(r)
        r["steps"] = r["steps"][:1]
        s1 = solve(r)
        with open(os.path.join(s1["dir"], "summary.json")) as fh:
            u = json.load(fh)["steps"][0]["probes"]["soleus"]["displacement"]
        print(f"  {name}: soleus end at 10 N (mm) {np.array2string(1e3 * np.array(u), precision=4)}", flush=True)
    s = solve(column(**law, mode=None))
    print(f"  default increments to 400 N: {s['status']}, last level {s['last']:g} N, {s['cutbacks']} cut-backs, "
          f"{s['newton']} Newton, soleus {s['soleus_mm']:.3f} mm", flush=True)


def soleus_element_strains(problem, X) -> np.ndarray:
    """Ē (not clipped) of the soleus (the first beam), one row per element."""
    blk = problem.blocks[0]
    G, _, mat = blk.parts[0]
    E = part_strains(blk, problem.exchange.local_state(X), G, mat)
    return E.reshape(E.shape[0], -1)


def column_measures(pb, X) -> tuple[np.ndarray, float]:
    """(3 smallest singular values of the Jacobi-scaled Jacobian on the free DOFs and multipliers,
    lowest eigenvalue of the scaled soleus block) at state X; multiplier rows and columns are
    scaled by the norm of their scaled coupling to the beams."""
    pb.jacobian(None, X, pb.J, pb.J)
    M = pb.J.copy()
    M.convert("seqaij")
    A = M.convert("dense").getDenseArray().copy()
    M.destroy()
    nodes = pb.layout.perm[:pb.model.n_nodes]
    beam = (18 * nodes[:, None] + np.arange(18)).ravel()
    soleus = np.zeros(A.shape[0], dtype=bool)
    soleus[beam[:18 * pb.model.beams[0].n_nodes]] = True
    free = ~pb.fixed_mask
    b = np.flatnonzero(np.isin(np.arange(A.shape[0]), beam) & free)
    m = np.flatnonzero(~np.isin(np.arange(A.shape[0]), beam) & free)
    d = 1.0 / np.sqrt(np.abs(np.diag(A)[b]))
    coupling = np.linalg.norm(A[np.ix_(m, b)] * d[None, :], axis=1)
    s = np.concatenate([d, np.where(coupling > 0.0, 1.0 / np.where(coupling > 0.0, coupling, 1.0), 1.0)])
    rows = np.concatenate([b, m])
    sv = np.linalg.svd(A[np.ix_(rows, rows)] * s[:, None] * s[None, :], compute_uv=False)[-3:]
    K = A[np.ix_(b, b)] * d[:, None] * d[None, :]
    sol = soleus[b]
    return sv[::-1], float(np.linalg.eigvalsh(0.5 * (K + K.T)[np.ix_(sol, sol)])[0])


def column_fold() -> None:
    from ancf_petsc.solving.records import LoadStepFailure
    law = published_law("solver_default_2025")
    raw = column(**law, mode="unilateral", steps=LEVELS[:7] + [85, 88, 89, 89.5])
    raw["contact"]["fade"] = "newton"
    run = _run(raw)
    pb = run.problem

    def on_level(rec):
        sv, low = column_measures(pb, pb.X)
        per = soleus_element_strains(pb, pb.X)
        print(f"  {rec.load_factor:g} N ({rec.iterations} Newton): smallest scaled singular values "
              f"{np.array2string(sv, precision=2)}, soleus block {low:.3e}, soleus Ē per element min "
              + " ".join(f"{e.min():.3f}" for e in per) + ", max " + " ".join(f"{e.max():.3f}" for e in per), flush=True)
    try:
        run.stepper.run(list(raw["steps"]), on_level)
        print("  column: all levels reached", flush=True)
    except LoadStepFailure as exc:
        print(f"  column stops: {str(exc)[:160]}", flush=True)
    finally:
        run.stepper.close()
        run.destroy()
    lone = column(**law, mode=None, steps=[2.5, 3, 3.5, 4, 4.2, 4.3, 4.4, 4.45, 4.5, 5, 6])
    lone.pop("loads")
    lone["boundary_conditions"].append({"beam": "soleus", "node": "last", "displacement": {"r": {"x": 1.0e-3}}})
    s = solve(lone)
    with open(os.path.join(s["dir"], "summary.json")) as fh:
        steps = json.load(fh)["steps"]
    print(f"  lone soleus, r_x of its end prescribed [mm]: {s['status']} {s['message'][:100]}; reaction [N] "
          + ", ".join(f"{st['load_factor']:g} mm: {st['reactions']['soleus.8'][0]:.3f}" for st in steps), flush=True)


def traction() -> None:
    def run(law: dict, mode, load: str, fade_mode: str = "newton", elements: int = 4, at_10: bool = False) -> str:
        raw = column(**law, mode=mode, elements=elements)
        raw["loads"] = [{"beam": "soleus", "node": "last", load: [1.0, 0.0, 0.0]}]
        if mode:
            raw["contact"]["fade"] = fade_mode
        s = solve(raw)
        out = (f"{s['status']}, last level {s['last']:g} N, {s['cutbacks']} cut-backs, {s['newton']} Newton, "
               f"soleus {s['soleus_mm']:.5f} mm")
        if not at_10:
            return out
        raw["steps"] = [10.0]
        r = _run(raw)
        try:
            r.stepper.run([10.0], lambda *_: None)
            E = fibre_strains(r.problem, r.problem.X)
            return out + f"; Ē at 10 N {E.min():.3f} … {E.max():.3f}"
        finally:
            r.stepper.close()
            r.destroy()

    for name in SETS:
        law = published_law(name)
        for mode in (None, "unilateral"):
            for load in ("force", "traction_force"):
                print(f"{name}: {mode or 'lone soleus'}, {load}: {run(law, mode, load, at_10=True)}", flush=True)
        for mode, fade_mode, elements in (("unilateral", "settle", 4), ("sliding", "settle", 4),
                                          ("sliding", "newton", 4), ("unilateral", "newton", 8)):
            print(f"{name}: {mode}, traction_force, fade {fade_mode}, {elements} elements: "
                  f"{run(law, mode, 'traction_force', fade_mode, elements)}", flush=True)


def hand_newton(pb, X, load: float, tol: float, max_it: int = 40) -> tuple[bool, int]:
    """Plain Newton at ``load`` from X (in place): MUMPS LU of the assembled Jacobian, no
    predictor, no line search, the contact's active set kept; (converged, iterations)."""
    from petsc4py import PETSc
    ksp = PETSc.KSP().create()
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    ksp.getPC().setFactorSolverType("mumps")
    F, dX = pb.F.duplicate(), X.duplicate()
    pb.load_factor = load
    try:
        for k in range(max_it + 1):
            pb.contact.allow_update = False
            pb.residual(None, X, F)
            if F.norm() <= tol:
                return pb.contact.converged(), k
            pb.contact.allow_update = False
            pb.jacobian(None, X, pb.J, pb.J)
            ksp.setOperators(pb.J)
            ksp.solve(F, dX)
            X.axpy(-1.0, dX)
        return False, max_it
    finally:
        for o in (ksp, F, dX):
            o.destroy()


def column_limit() -> None:
    """The solver_default_2025 column (unilateral, fade newton) through Table 1's levels to 90 N
    and 90.711 N, then Newton by hand from there at loads nearing where the column stops
    (``fade solver_default_2025:unilateral``: 90.7114 N): the smallest singular values of the
    Jacobi-scaled Jacobian, the soleus block's lowest eigenvalue and the gastrocnemii's ends."""
    raw = column(**published_law("solver_default_2025"), mode="unilateral", steps=LEVELS[:8] + [90.711])
    raw["contact"]["fade"] = "newton"
    run = _run(raw)
    pb = run.problem
    ends = np.cumsum([b.n_nodes for b in pb.model.beams]) - 1
    nodes = pb.layout.perm[ends]

    def show(load, X, its=""):
        sv, low = column_measures(pb, X)
        x = X.getArray(readonly=True).reshape(-1, 6, 3)[nodes, 0] - pb.q0.getArray(readonly=True).reshape(-1, 6, 3)[nodes, 0]
        print(f"  {load:.7g} N{its}: smallest scaled singular values {np.array2string(sv, precision=3)}, soleus block "
              f"{low:.4e}, end y [mm] medial gastrocnemius {1e3 * x[1, 1]:.4f}, lateral {1e3 * x[2, 1]:.4f}", flush=True)
    try:
        run.stepper.run(list(raw["steps"]), lambda rec: None)
        X = pb.X.copy()
        show(raw["steps"][-1], X)
        tol = run.stepper.solver.snes.getTolerances()[1]
        for load in (90.7111, 90.7112, 90.7113, 90.71133, 90.71136):
            ok, its = hand_newton(pb, X, load, tol)
            if not ok:
                print(f"  {load:.7g} N: Newton by hand does not converge ({its} iterations)", flush=True)
                break
            pb.checkpoint()
            show(load, X, f" ({its} Newton)")
    finally:
        run.stepper.close()
        run.destroy()

def main(argv: list[str]) -> int:
    from ancf_verify.cli import study_parts
    parts = {"reference": reference, "bulk": bulk, "eigen": eigen, "sets": sets, "fold": fold, "fade": fade,
             "column_fold": column_fold, "column_limit": column_limit, "traction": traction}
    argv = study_parts("goh_published_sets.py", __doc__, parts, argv, "; or fade set:mode ...: those columns")
    from mpi4py import MPI  # noqa: F401
    import petsc4py
    petsc4py.init([])
    if argv[:1] == ["fade"] and len(argv) > 1:          # fade set:mode ...
        print("## fade", flush=True)
        fade(argv[1:])
        return 0
    for name in argv or list(parts):
        if name not in parts:
            print(f"goh_published_sets: unknown part {name!r}; choose from {list(parts)}", file=sys.stderr)
            return 2
        print(f"## {name}", flush=True)
        parts[name]()
    return 0
