"""Mesh convergence of a solid quantity: Richardson extrapolation, settled sequences, goal values."""
from __future__ import annotations

import numpy as np


# --------------------------------------------------------------------------------------------
# Reference value, errors, goal
# --------------------------------------------------------------------------------------------
def richardson(solids: list) -> tuple[np.ndarray, float, str]:
    """Converged solid answer from the finest three meshes (h ∝ DOFs^-1/3, fitted order p).

    Returns (u_ref, relative uncertainty, how).  Falls back to the finest mesh with the last
    change as its uncertainty if the changes of |u| do not shrink monotonically or p is outside
    [0.5, 6]; otherwise the uncertainty is the distance from the finest mesh to u_ref."""
    u = np.array([s["u"] for s in solids[-3:]])
    h = np.array([s["dofs"] for s in solids[-3:]], dtype=float) ** (-1.0 / 3.0)
    q = np.linalg.norm(u, axis=1)
    fine, last = u[-1], float(np.linalg.norm(u[-1] - u[-2]) / np.linalg.norm(u[-1]))
    d1, d2 = q[1] - q[0], q[2] - q[1]
    if len(solids) < 3 or d1 * d2 <= 0 or abs(d2) >= abs(d1):
        return fine, last, "finest mesh: the changes of the finest three do not shrink monotonically"

    def g(p):   # (q1 - q0)/(q2 - q1) = (h0^p - h1^p)/(h1^p - h2^p)
        return (h[0] ** p - h[1] ** p) / (h[1] ** p - h[2] ** p) - d1 / d2

    lo, hi = 0.5, 6.0
    if g(lo) * g(hi) > 0:
        return fine, last, "finest mesh: fitted order outside [0.5, 6]"
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if g(lo) * g(mid) > 0 else (lo, mid)
    p = 0.5 * (lo + hi)
    ref = u[-1] + (u[-1] - u[-2]) / ((h[1] / h[2]) ** p - 1.0)
    unc = float(np.linalg.norm(ref - fine) / np.linalg.norm(ref))
    return ref, unc, f"Richardson, finest three meshes, order p = {p:.2f}"


def settled(rows: list, model: str, target: float) -> dict | None:
    """First run of ``model`` (coarse to fine) from which every finer run is within ``target``:
    a lucky crossing of a coarse run does not count."""
    fam = [r for r in rows if r["model"] == model]
    for i in range(len(fam)):
        if all(r["err"] <= target for r in fam[i:]):
            return fam[i]
    return None


def goal(rows: list, target: float = 0.01, factor: float = 20.0) -> dict:
    """Cheapest settled ANCF run and settled solid run within ``target``; the speed-ups."""
    anc = [r for r in (settled(rows, m, target) for m in ("ANCF 3pt", "ANCF 2pt")) if r is not None]
    anc = min(anc, key=lambda r: r["wall"], default=None)
    sol = settled(rows, "solid P2 tet", target)
    finest = [r for r in rows if r["model"] == "solid P2 tet"][-1]
    nan = float("nan")
    out = {"ancf": anc, "solid": sol, "finest": finest, "equal": nan, "equal_mesh": nan,
           "vs_finest": nan, "factor": factor, "target": target}
    if anc is not None:
        out["vs_finest"] = finest["wall"] / anc["wall"]
        if sol is not None:
            out["equal"] = sol["wall"] / anc["wall"]
            out["equal_mesh"] = (sol["wall"] + sol["mesh"]) / anc["wall"]
    out["holds"] = bool(out["equal"] >= factor)            # NaN compares False
    out["holds_finest"] = bool(out["vs_finest"] >= factor)
    return out
