"""The section order as a rung (issue 42): 3363, 33103 and 33153 against each other, beam theory
and the committed 3D-solid answers (no new solid runs); each part prints a markdown table
(docs/locking.md, "Orders 3 and 4"; docs/studies.md, "The section order as a rung").  The
command line is ``scripts/section_orders.py`` (ancf_verify.cli.section_orders, its docstring lists
the parts)."""
from __future__ import annotations

import copy
import csv
import dataclasses
import math
import os
import tempfile
import time

import numpy as np
import yaml

from ancf_petsc.workflows.timing import best_times
from ancf_verify.paths import CONFIGS, ROOT

ORDERS = {"3363": 2, "33103": 3, "33153": 4}
LOCKINGS = ("none", "ecm", "mixed")


def lockings(element: str) -> tuple[str, ...]:
    """The remedies the element accepts (33103, 33153 refuse ``ecm``: ``uniaxial`` shows why)."""
    from ancf_petsc.physics.elements import ELEMENTS
    return tuple(lk for lk in LOCKINGS if lk in ELEMENTS[element].remedies)


def load(name: str) -> dict:
    with open(os.path.join(CONFIGS, name)) as fh:
        return yaml.safe_load(fh)


def solve(raw: dict, tmp: str, tag: str, locking: str | None = None) -> dict:
    """``raw`` solved in-process into tmp/tag; the summary with its wall time.  ``locking``: every
    beam's remedy set past the config's checks (the refused ``ecm`` of the higher orders, measured)."""
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    raw = copy.deepcopy(raw)
    raw["output"] = {"dir": os.path.join(tmp, tag), "vtk": False}
    t0 = time.perf_counter()
    spec = parse_config(raw, base_dir=CONFIGS)
    for b in spec.beams:
        b.locking = locking or b.locking
    s = run_model(spec, log=lambda *_: None).summary
    s["wall"] = time.perf_counter() - t0
    return s


def _head(first: str, cols: list[str]) -> None:
    print(f"| {first} | " + " | ".join(cols) + " |\n|---|" + "---:|" * len(cols))


def _pct(x: float) -> str:
    return f"{100 * x:+.3f} %"


# ----------------------------------------------------------------------------- cantilever
def cantilever_raw(element: str, locking: str, length: float, fix: str = "clamped", elements: int = 16) -> dict:
    raw = load("bending_neohookean.yaml")
    b = raw["beams"][0]
    b.update(element=element, elements=elements)
    raw["boundary_conditions"][0]["fix"] = fix
    raw["geometry"]["length"] = length
    raw["loads"][0]["traction_force"] = [0.0, 0.0, 1e-3 * beam_theory(length)[0]]
    raw["steps"] = [1.0]
    return raw


def beam_theory(length: float, h: float = 0.01, mu: float = 1.0e6, K: float = 50.0e6) -> tuple:
    """(P, w_EB, w_Timoshenko) of a tip force giving w_EB = L / 1000 on the cantilever."""
    E = 9.0 * K * mu / (3.0 * K + mu)
    nu = (3.0 * K - 2.0 * mu) / (2.0 * (3.0 * K + mu))
    kappa = 10.0 * (1.0 + nu) / (12.0 + 11.0 * nu)             # Cowper, square section
    P = 3.0 * E * h ** 4 / 12.0 / length ** 2
    w_eb = P * length ** 3 / (3.0 * E * h ** 4 / 12.0)
    return P, w_eb, w_eb + P * length / (kappa * mu * h * h)


def cantilever() -> None:
    """Roots: ``clamped`` (the config's; the root section can neither contract nor warp) and
    ``plane`` (a face on a frictionless plane: free to contract, held plane)."""
    _head("root, element, locking", [f"L/h = {r}: w/w_EB − 1 / w/w_Timoshenko − 1" for r in (10, 40)])
    with tempfile.TemporaryDirectory() as tmp:
        for fix in ("clamped", "plane"):
            for el in ORDERS:
                for lock in LOCKINGS:
                    cells = []
                    for L in (0.1, 0.4):
                        s = solve(cantilever_raw(el, "none", L, fix), tmp, f"c{el}{lock}{L}{fix}", locking=lock)
                        P, w_eb, w_t = beam_theory(L)
                        w = s["steps"][-1]["probes"]["tip"]["displacement"][2] / 1e-3
                        cells.append(f"{_pct(w / w_eb - 1)} / {_pct(w / w_t - 1)}")
                    refused = "" if lock in lockings(el) else " (refused)"
                    print(f"| {fix}, {el}, {lock}{refused} | " + " | ".join(cells) + " |", flush=True)


# ----------------------------------------------------------------------------- uniaxial
def uniaxial() -> None:
    from ancf_petsc.physics.materials import NeoHookean
    from ancf_petsc.physics.reference_solutions import uniaxial_stretches
    _head("element", [f"locking: {lk}, max |u/u_exact − 1|" for lk in LOCKINGS])
    with tempfile.TemporaryDirectory() as tmp:
        for el in ORDERS:
            cells = []
            for lock in LOCKINGS:
                raw = load("uniaxial_neohookean.yaml")
                raw["beams"][0].update(element=el)
                s = solve(raw, tmp, f"u{el}{lock}", locking=lock)
                area = next(iter(s["sections"].values()))["area"]
                err = max(abs(st["probes"]["tip"]["displacement"][0]
                              / ((uniaxial_stretches(NeoHookean(1e6, 50e6), st["load_factor"] * 45.0 / area)[0] - 1) * 0.1) - 1)
                          for st in s["steps"])
                cells.append(f"{err:.1e}")
            print(f"| {el} | " + " | ".join(cells) + " |", flush=True)


# ----------------------------------------------------------------------------- solids
def solids() -> None:
    from ancf_verify.bars.cases import CASES, ancf_config
    with open(os.path.join(ROOT, "docs", "solid_comparison.csv"), newline="") as fh:
        refs = {r["case"]: np.array([float(r[f"ref_u{c}_m"]) for c in "xyz"]) for r in csv.DictReader(fh)}
    _head("element, locking", [f"{c.key}, 8 el." for c in CASES])
    with tempfile.TemporaryDirectory() as tmp:
        for el in ORDERS:
            for lock in lockings(el):
                cells = []
                for case in CASES:
                    raw = ancf_config(dataclasses.replace(case, element=el), 8, 2, "unused")
                    raw["beams"][0]["locking"] = lock
                    s = solve(raw, tmp, f"s{el}{lock}{case.key}")
                    u = np.array(s["steps"][-1]["probes"]["tip"]["displacement"])
                    ref = refs[case.key]
                    cells.append(f"{_pct(np.linalg.norm(u) / np.linalg.norm(ref) - 1)}")
                print(f"| {el}, {lock} | " + " | ".join(cells) + " |", flush=True)


# ----------------------------------------------------------------------------- untwist
def _untwist(st: dict) -> float:
    ry = np.array(st["probes"]["tip_r_y"]["value"])
    ry0 = ry - np.array(st["probes"]["tip_r_y"]["displacement"])
    return math.degrees(math.atan2(ry0[2], ry0[1]) - math.atan2(ry[2], ry[1]))


def untwist() -> None:
    from ancf_verify.fibres.beams import run_ancf
    from ancf_verify.fibres.cases import ANCF, ANCF_MIXED, LAWS, case_key, make_case
    from ancf_verify.fibres.report import read_csv, runs_of
    fib = runs_of(read_csv(os.path.join(ROOT, "docs", "solid_fibres.csv")))
    _head("element, locking", ["pretwisted_bar 8 el.: elongation [mm] / untwist [°]", "32 el."]
          + [f"{law.key} K/μ = 50, 16 el.: rotation / solid − 1" for law in LAWS])
    with tempfile.TemporaryDirectory() as tmp:
        for el in ORDERS:
            for lock in ("none", "mixed"):
                cells = []
                for n in (8, 32):
                    raw = load("pretwisted_bar.yaml")
                    raw["beams"][0].update(element=el, locking=lock, elements=n)
                    raw["petsc"] = {"snes_linesearch_type": "bt"}
                    st = solve(raw, tmp, f"p{el}{lock}{n}")["steps"][-1]
                    cells.append(f"{1e3 * st['probes']['tip']['displacement'][0]:.5f} / {_untwist(st):.4f}")
                for law in LAWS:
                    case = dataclasses.replace(make_case(law, 50.0), element=el)
                    r = run_ancf(case, 16, tmp, ANCF if lock == "none" else ANCF_MIXED)
                    cells.append(_pct(r["rot"] / fib[case_key(law.key, 50.0)]["ref_rot"] - 1))
                print(f"| {el}, {lock} | " + " | ".join(cells) + " |", flush=True)


# ----------------------------------------------------------------------------- soft matrix
def soft() -> None:
    from petsc4py import PETSc
    # order 3-4 with ``mixed``: MUMPS's first workspace estimate is short (INFOG(1) = -9, delayed
    # pivots); more room, the same factorisation
    PETSc.Options().setValue("mat_mumps_icntl_14", 100)
    from ancf_verify.fibres.cases import ANCF, ANCF_MIXED
    from ancf_verify.fibres.report import read_csv
    from ancf_verify.soft_matrix.beams import run_beam
    from ancf_verify.soft_matrix.cases import make_case
    rows = [r for r in read_csv(os.path.join(ROOT, "docs", "solid_soft_matrix.csv"))
            if r["model"].startswith("solid") and r["kind"] == "end" and float(r["load_N"]) == 200.0]
    finest = rows[-1]
    ux, mean = float(finest["ux_m"]), float(finest["ux_mean_m"])
    print(f"solid ({finest['resolution']}): centroid u_x {1e3 * ux:.4f} mm, face mean {1e3 * mean:.4f} mm; "
          "the solid's centroid by mesh: " + ", ".join(f"{r['resolution']} {1e3 * float(r['ux_m']):.4f}" for r in rows) + "\n")
    _head("element, locking, elements", ["Newton", "centroid u_x [mm]", "/ solid − 1", "face-mean u_x [mm]",
                                         "/ solid − 1", "rotation [°]", "wall [s]"])
    with tempfile.TemporaryDirectory() as tmp:
        for el in ORDERS:
            for lock, model in (("none", ANCF), ("mixed", ANCF_MIXED)):
                for n in (4, 8):
                    case = dataclasses.replace(make_case(), element=el)
                    r = run_beam(case, n, tmp, model, "traction_force")
                    print(f"| {el}, {lock}, {n} | {r['its']} | {1e3 * r['u'][0]:.4f} | {_pct(r['u'][0] / ux - 1)} | "
                          f"{1e3 * r['u_mean'][0]:.4f} | {_pct(r['u_mean'][0] / mean - 1)} | {r['rot']:.3f} | "
                          f"{r['wall']:.1f} |", flush=True)


# ----------------------------------------------------------------------------- column
CONTACTS = {"sliding": {"mode": "sliding"}, "unilateral": {"mode": "unilateral"},
            "coulomb 0.3": {"mode": "sliding", "tangential": {"law": "coulomb", "friction": 0.3}}}


def column() -> None:
    _head("element (DOFs)", [f"{c}: wall [s] / Newton / soleus 400 N [mm]" for c in CONTACTS])
    with tempfile.TemporaryDirectory() as tmp:
        for el in ORDERS:
            cells, dofs = [], 0
            for name, contact in CONTACTS.items():
                raw = load("achilles_type3_psi45.yaml")
                for b in raw["beams"]:
                    b["element"] = el
                raw["contact"] = contact
                s = solve(raw, tmp, f"col{el}{name}")
                dofs = s["dofs"]
                ok = s["status"] == "completed"
                cells.append(f"{s['wall']:.1f} / {sum(st['iterations'] for st in s['steps'])} / "
                             + (f"{1e3 * s['steps'][-1]['probes']['soleus']['displacement'][0]:.4f}" if ok
                                else f"stops at {s['steps'][-1]['load_factor'] if s['steps'] else 0:g} N"))
            print(f"| {el} ({dofs}) | " + " | ".join(cells) + " |", flush=True)


# ----------------------------------------------------------------------------- kernel
def kernel_block(name: str, n_el: int, law):
    """qe, G, w of ``n_el`` elements of ``name`` (a pretwisted ellipse, 2 axial points, the
    element's default section rule max(6, 2 × order)) and the law bound to helical fibres (GOH)."""
    from ancf_petsc.physics import element3363 as el
    from ancf_petsc.physics.cubature import gauss_legendre
    from ancf_petsc.physics.elements import ELEMENTS
    from ancf_petsc.physics.fibres import fibre_directions
    from ancf_petsc.physics.geometry import reference_nodal_vectors
    from ancf_petsc.physics.section import make_ellipse
    layout = ELEMENTS[name]
    V = layout.block.vectors_per_node
    sec = make_ellipse((0.004, 0.0025), (0.003, 0.0), max(6, layout.section_degree))
    xa, wa = gauss_legendre(2)
    xi, y, z = el.tensor_points(xa, sec.points)
    _, dN = layout.shape_functions(xi, y, z)
    x = np.linspace(0.0, 0.07, 2 * n_el + 1)
    q0 = reference_nodal_vectors(x, sec.centroid, 0.07, 45.0, (0.0, 0.0), V)
    conn = 2 * np.arange(n_el)[:, None] + np.arange(3)[None, :]
    q0e = q0[conn].reshape(n_el, 3 * V, 3)
    G, det = el.reference_gradients(q0e, dN)
    rng = np.random.default_rng(0)
    # bench_kernel's state: 5 % axial stretch, noise 0.1 % of the element length on r, 1e-3 on the rest
    scale = np.where(np.arange(3 * V) % V == 0, x[2] - x[0], 1.0)[None, :, None]
    qe = q0e * np.array([1.05, 1.0, 1.0]) + 1e-3 * rng.standard_normal(q0e.shape) * scale
    w = det * (np.repeat(wa, len(sec.weights)) * np.tile(sec.weights, 2))[None]
    if not hasattr(law, "with_directions"):
        return qe, G, w, law
    xg = x[0:-1:2, None] + 0.5 * (xi[None, :] + 1.0) * (x[2] - x[0])
    P = np.broadcast_to(sec.centroid + np.column_stack([y, z]), xg.shape + (2,)).reshape(-1, 2)
    a0 = fibre_directions(xg.ravel(), P, 0.07, 45.0, (0.0, 0.0), sec.centroid)
    return qe, G, w, law.with_directions(a0.reshape((1,) + xg.shape + (3,)))


def kernel(n_el: int = 64, repeat: int = 30) -> None:
    """µs per Gauss point and per element, residual and residual + tangent, neo-Hookean and GOH
    (scripts/bench_kernel.py's state and laws), best of ``repeat`` interleaved calls."""
    from ancf_petsc.physics import kernels
    from ancf_petsc.physics.goh import GOH
    from ancf_petsc.physics.materials import NeoHookean
    _head("element (DOFs, GP per element)", ["law", "residual µs/GP", "residual + tangent µs/GP",
                                             "residual + tangent µs/element"])
    for name in ORDERS:
        for lname, law in (("neo-Hookean", NeoHookean(1e6, 5e7)), ("GOH", GOH(1e6, 5e7, 2e6, 5.0, 0.1))):
            qe, G, w, m = kernel_block(name, n_el, law)
            a, b = best_times([lambda: kernels.internal_force(qe, G, w, m),
                          lambda: kernels.internal_force_and_tangent(qe, G, w, m)], repeat)
            print(f"| {name} ({3 * qe.shape[1]}, {w.shape[1]}) | {lname} | {1e6 * a / w.size:.3f} | "
                  f"{1e6 * b / w.size:.3f} | {1e6 * b / n_el:.1f} |", flush=True)


PARTS = {"cantilever": cantilever, "uniaxial": uniaxial, "solids": solids, "untwist": untwist, "soft": soft,
         "column": column, "kernel": kernel}


