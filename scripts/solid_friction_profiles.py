"""Where the friction acts: contact pressure and friction force along the tendon, solid and beams.

Per interface and axial bin [x, x + Δx) of the reference configuration: the compressive and the
tensile normal force per length, q± = Σ_bin w p^± / Δx [N/m] (Coulomb's bound is μ q⁺), and the
friction force per length on the solid's slave body (medial, lateral, medial), f_x [N/m].
Solid: the slave Gauss points (w the reference area weight, p the interpolated pressure).
ANCF: the contact points of results.h5 (``area``, ``pressure``, ``shear_stress``, ``x0``).
"""
from __future__ import annotations

import os

import numpy as np

import solid_friction as sf
import solid_friction_report as rep
import verify_solid_contact as vsc

FIELDS = ["model", "variant", "resolution", "interface", "load_N", "x_lo_m", "x_hi_m", "q_plus_N_per_m",
          "q_minus_N_per_m", "fx_N_per_m"]
BIN = 2.5e-3


def binned(x, pw, fx) -> list:
    """(x_lo, q⁺, q⁻, f_x) per bin of BIN along [0, L] from point values p·w [N] and f_x [N]."""
    edges = np.arange(0.0, vsc.LENGTH + 0.5 * BIN, BIN)
    k = np.clip(np.digitize(x, edges) - 1, 0, len(edges) - 2)
    out = []
    for b in range(len(edges) - 1):
        m = k == b
        out.append((edges[b], edges[b + 1], float(np.maximum(pw[m], 0).sum()) / BIN,
                    float(np.minimum(pw[m], 0).sum()) / BIN, float(fx[m].sum()) / BIN))
    return out


def solid_profile(secs, psi: float, h: float, mu: float, level: float, stick: float = 100.0) -> list:
    """The solid with friction μ (0: frictionless) solved to ``level`` along Table 1's levels."""
    P, _ = vsc.tendon_problem(secs, psi, h, "sliding", problem_class=sf.FrictionProblem, mu=mu, stick=stick)
    P.solve_path([F for F in vsc.LOADS if F <= level], max_increment=50.0)
    c = P.residual(P.uvec, P.zvec)[2]
    rows = []
    for fr, q in zip(P.fr, c["friction"]["per"]):
        itf = fr.itf
        x = itf.slave_points(P.X)[:, 0]
        on = itf.on
        pw = np.where(on, q["p"], 0.0) * itf.w
        fx = -itf.w * q["sigma"][:, 0]
        for lo, hi, qp, qm, f in binned(x, pw, fx):
            rows.append({"model": rep.SOLID, "variant": f"mu {mu:g}", "resolution": f"h {h * 1e3:.2f} mm",
                         "interface": itf.name, "load_N": level, "x_lo_m": lo, "x_hi_m": hi,
                         "q_plus_N_per_m": qp, "q_minus_N_per_m": qm, "fx_N_per_m": f})
    return rows


def ancf_contact(psi: float, elements: int, mu: float, level: float, aug, out: str,
                 space: str | None = None) -> dict | None:
    """The ANCF column (verify_solid_friction.ancf_config; μ = 0: frictionless; ``space`` a
    rep.SPACES name, None the default pressure space) to ``level``, written to ``out``: the last
    level's contact points (interface, x0, pressure, area, shear_stress or zeros), None if the run
    did not complete."""
    import h5py
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    from verify_solid_friction import ancf_config
    raw = ancf_config(psi, elements, mu, aug, out, space)
    if mu == 0.0:
        del raw["contact"]["tangential"]
    raw["steps"] = [float(F) for F in vsc.LOADS if F <= level]
    res = run_model(parse_config(raw, base_dir=vsc.CONFIGS), log=lambda *_: None)
    if res.status != "completed":
        return None
    with h5py.File(os.path.join(out, "results.h5"), "r") as f:
        g = f["steps"][sorted(f["steps"])[-1]]["contact"]
        pts = {k: g[k][:] for k in ("interface", "x0", "pressure", "area")}
        pts["shear_stress"] = g["shear_stress"][:] if "shear_stress" in g else np.zeros((len(pts["pressure"]), 3))
    return pts


def ancf_profile(psi: float, elements: int, mu: float, level: float, aug, tmp: str, space: str | None = None) -> list:
    """The ANCF column's profiles (``ancf_contact``) to ``level``."""
    out = os.path.join(tmp, f"profile_{elements}_{mu:g}_{aug}_{space}".replace(" ", "_"))
    pts = ancf_contact(psi, elements, mu, level, aug, out, space)
    if pts is None:
        return []
    rows = []
    itf, x0, p, area = pts["interface"], pts["x0"][:, 0], pts["pressure"], pts["area"]
    sigma = pts["shear_stress"][:, 0]
    for i, name in enumerate(rep.IFACES):
        m = itf == i
        # force on the solid's slave body; shear_stress is the first beam's (config order) on
        # the second: the slave is the second on mg_sol, lg_sol and the first on lg_mg
        fx = (-1.0 if name == "lg_mg" else 1.0) * area[m] * sigma[m]
        for lo, hi, qp, qm, fxb in binned(x0[m], p[m] * area[m], fx):
            rows.append({"model": rep.ANCF, "variant": f"mu {mu:g}" + ("" if aug is None else f", augmentation {aug:g}")
                         + (f"{rep.SPACE}{space}" if space else ""),
                         "resolution": f"{elements} el.", "interface": name, "load_N": level, "x_lo_m": lo,
                         "x_hi_m": hi, "q_plus_N_per_m": qp, "q_minus_N_per_m": qm, "fx_N_per_m": fxb})
    return rows


def read(path: str) -> list:
    import csv
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def write(path: str, rows: list) -> None:
    import csv
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=FIELDS)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6e}" if isinstance(v, float) else v) for k, v in r.items() if k in FIELDS})


class BeamFreeZone:
    """A diagnostic for the beams: no friction below x = ``zone`` [m] of the reference
    configuration.  The Coulomb law holds per tangential multiplier function (friction.py), so
    the functions whose support is centred below ``zone`` (the mean reference x of their contact
    points, weighted by the points' weights) get the bound μ ẑ_k = 0 in the return mapping (and
    no derivative of it): their y_k go to zero.  Every beam has ``elements`` elements over
    ``length``.  Use as a context manager around run_model (serial runs)."""

    def __init__(self, zone: float, elements: int, length: float = vsc.LENGTH):
        self.zone, self.elements, self.length = zone, elements, length

    def __enter__(self):
        from ancf_petsc.contact import friction as fm
        self.fm, self.orig, self.orig_map = fm, fm.CoulombFriction.evaluate, fm.return_map
        zone, E, L, orig, orig_map = self.zone, self.elements, self.length, self.orig, self.orig_map

        def evaluate(law, c, st, x_of):
            pts, wp = law.points, law.points.w[c.local]
            x = (pts.eA[c.local] % E + 0.5 * (pts.xi[c.local] + 1.0)) * L / E
            weight = c.Phi @ wp
            centre = (c.Phi @ (wp * x)) / np.where(weight > 0.0, weight, 1.0)
            free = (weight > 0.0) & (centre < zone)
            fm.return_map = lambda a, nbar, bound, held=True: orig_map(a, nbar, np.where(free, 0.0, bound), held)
            try:
                ev = orig(law, c, st, x_of)
            finally:
                fm.return_map = orig_map
            ev.bound[free] = 0.0
            ev.g[free] = 0.0
            return ev
        fm.CoulombFriction.evaluate = evaluate
        return self

    def __exit__(self, *exc):
        self.fm.CoulombFriction.evaluate = self.orig
        self.fm.return_map = self.orig_map
        return False
