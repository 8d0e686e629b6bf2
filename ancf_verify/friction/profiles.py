"""Pressure and friction force along the tendon per interface, solid and beams (profile CSV)."""
from __future__ import annotations

import os

import numpy as np

from ancf_verify.contact.solid import tendon_problem
from ancf_verify.contact.tendon import LENGTH, LOADS, SOURCE
from ancf_verify.friction.beams import ancf_config
from ancf_verify.friction.model import FrictionProblem
from ancf_verify.friction.rows import IFACES, SOLID, SPACE, ancf_model, read_csv, write_sci


FIELDS = ["model", "variant", "resolution", "interface", "load_N", "x_lo_m", "x_hi_m", "q_plus_N_per_m",
          "q_minus_N_per_m", "fx_N_per_m"]

BIN = 2.5e-3


def binned(x, pw, fx) -> list:
    """(x_lo, q⁺, q⁻, f_x) per bin of BIN along [0, L] from point values p·w [N] and f_x [N]."""
    edges = np.arange(0.0, LENGTH + 0.5 * BIN, BIN)
    k = np.clip(np.digitize(x, edges) - 1, 0, len(edges) - 2)
    out = []
    for b in range(len(edges) - 1):
        m = k == b
        out.append((edges[b], edges[b + 1], float(np.maximum(pw[m], 0).sum()) / BIN,
                    float(np.minimum(pw[m], 0).sum()) / BIN, float(fx[m].sum()) / BIN))
    return out


def solid_profile(secs, psi: float, h: float, mu: float, level: float, stick: float = 100.0) -> list:
    """The solid with friction μ (0: frictionless) solved to ``level`` along Table 1's levels."""
    P, _ = tendon_problem(secs, psi, h, "sliding", problem_class=FrictionProblem, mu=mu, stick=stick)
    P.solve_path([F for F in LOADS if F <= level], max_increment=50.0)
    c = P.residual(P.uvec, P.zvec)[2]
    rows = []
    for fr, q in zip(P.fr, c["friction"]["per"]):
        itf = fr.itf
        x = itf.slave_points(P.X)[:, 0]
        on = itf.on
        pw = np.where(on, q["p"], 0.0) * itf.w
        fx = -itf.w * q["sigma"][:, 0]
        for lo, hi, qp, qm, f in binned(x, pw, fx):
            rows.append({"model": SOLID, "variant": f"mu {mu:g}", "resolution": f"h {h * 1e3:.2f} mm",
                         "interface": itf.name, "load_N": level, "x_lo_m": lo, "x_hi_m": hi,
                         "q_plus_N_per_m": qp, "q_minus_N_per_m": qm, "fx_N_per_m": f})
    return rows


def ancf_contact(psi: float, elements: int, mu: float, level: float, aug, out: str,
                 space: str | None = None, contact: dict | None = None, element: str | None = None) -> dict | None:
    """The ANCF column (verify_solid_friction.ancf_config; μ = 0: frictionless; ``space`` a
    rows.SPACES name, None the default pressure space; ``contact``: more contact keys; ``element``:
    every beam's element, None the default) to ``level``, written to ``out``: the last
    level's contact points (interface, x0, pressure, area, shear_stress or zeros), None if the run
    did not complete."""
    import h5py
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    raw = ancf_config(psi, elements, mu, aug, out, space, contact, element)
    if mu == 0.0:
        del raw["contact"]["tangential"]
    raw["steps"] = [float(F) for F in LOADS if F <= level]
    res = run_model(parse_config(raw, base_dir=SOURCE.configs), log=lambda *_: None)
    if res.status != "completed":
        return None
    with h5py.File(os.path.join(out, "results.h5"), "r") as f:
        g = f["steps"][sorted(f["steps"])[-1]]["contact"]
        pts = {k: g[k][:] for k in ("interface", "x0", "pressure", "area")}
        pts["shear_stress"] = g["shear_stress"][:] if "shear_stress" in g else np.zeros((len(pts["pressure"]), 3))
    return pts


def ancf_profile(psi: float, elements: int, mu: float, level: float, aug, tmp: str, space: str | None = None,
                 contact: dict | None = None, element: str | None = None) -> list:
    """The ANCF column's profiles (``ancf_contact``) to ``level`` (model label: rows.ancf_model)."""
    out = os.path.join(tmp, (f"profile_{elements}_{mu:g}_{aug}_{space}" + (f"_{element}" if element else ""))
                       .replace(" ", "_"))
    pts = ancf_contact(psi, elements, mu, level, aug, out, space, contact, element)
    if pts is None:
        return []
    rows = []
    itf, x0, p, area = pts["interface"], pts["x0"][:, 0], pts["pressure"], pts["area"]
    sigma = pts["shear_stress"][:, 0]
    for i, name in enumerate(IFACES):
        m = itf == i
        # force on the solid's slave body; shear_stress is the first beam's (config order) on
        # the second: the slave is the second on mg_sol, lg_sol and the first on lg_mg
        fx = (-1.0 if name == "lg_mg" else 1.0) * area[m] * sigma[m]
        for lo, hi, qp, qm, fxb in binned(x0[m], p[m] * area[m], fx):
            rows.append({"model": ancf_model(element),
                         "variant": f"mu {mu:g}" + ("" if aug is None else f", augmentation {aug:g}")
                         + (f"{SPACE}{space}" if space else ""),
                         "resolution": f"{elements} el.", "interface": name, "load_N": level, "x_lo_m": lo,
                         "x_hi_m": hi, "q_plus_N_per_m": qp, "q_minus_N_per_m": qm, "fx_N_per_m": fxb})
    return rows


def read(path: str) -> list:
    return read_csv(path)


def write(path: str, rows: list) -> None:
    write_sci(path, FIELDS, rows)
