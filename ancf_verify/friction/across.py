"""Friction across the interfaces (profiles across the section), solid and beams."""
from __future__ import annotations

import os

import numpy as np

from ancf_verify.contact.solid import tendon_problem
from ancf_verify.contact.tendon import AXIS, INTERFACES, LENGTH, LOADS
from ancf_verify.friction.rows import ANCF, IFACES, SOLID, SPACE, num, read_csv, write_sci
from ancf_verify.paths import ROOT


FIELDS = ["model", "variant", "resolution", "interface", "load_N", "x_c_m", "s_lo_m", "s_hi_m", "weight_m2",
          "force_plus_N", "force_minus_N", "s_centre_m"]

WINDOW = 7e-3              # [m] axial width of a window (holds a Gauss station of the 4-element beams)

SBIN = 0.25e-3             # [m] width of an across bin

CSV = os.path.join(ROOT, "docs", "solid_friction_across.csv")

PNG = os.path.join(ROOT, "docs", "figures", "solid_friction_across.png")

PNG_ORDERS = os.path.join(ROOT, "docs", "figures", "solid_friction_across_orders.png")


def untwist(X: np.ndarray, psi: float) -> np.ndarray:
    """Section coordinates P (n, 2) of reference points X (n, 3): the inverse of geometry.place."""
    th = -np.deg2rad(psi) * X[:, 0] / LENGTH
    a = np.asarray(AXIS)
    d = X[:, 1:] - a
    c, s = np.cos(th), np.sin(th)
    return a + np.column_stack([c * d[:, 0] - s * d[:, 1], s * d[:, 0] + c * d[:, 1]])


def across_coordinates(secs) -> dict:
    """Per interface a function P (n, 2) -> s [m]: the arc length along the interface curve of the
    section outline from the triple point (the twist axis, where the three subtendons meet) to
    the curve point nearest P."""
    from scipy.spatial import cKDTree
    out = {}
    for name, slave, _ in INTERFACES:
        cv = next(c for c, _ in secs[slave].loop if c.name == name)
        C = cv(np.linspace(0.0, cv.t_end, 2001))
        if np.linalg.norm(C[-1] - AXIS) < np.linalg.norm(C[0] - AXIS):
            C = C[::-1]
        arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(C, axis=0), axis=1))])
        tree = cKDTree(C)
        out[name] = (lambda P, tree=tree, arc=arc: arc[tree.query(P)[1]])
    return out


def solid_points(secs, psi: float, h: float, mu: float, level: float) -> dict:
    """{interface: {"x", "P", "p", "w"}} of the solid (friction μ; 0 frictionless) at ``level``."""
    from ancf_verify.friction.model import FrictionProblem
    P, _ = tendon_problem(secs, psi, h, "sliding", problem_class=FrictionProblem, mu=mu, stick=100.0)
    P.solve_path([F for F in LOADS if F <= level], max_increment=50.0)
    c = P.residual(P.uvec, P.zvec)[2]
    out = {}
    for fr, q in zip(P.fr, c["friction"]["per"]):
        itf = fr.itf
        X = itf.slave_points(P.X)
        out[itf.name] = {"x": X[:, 0], "P": untwist(X, psi), "p": np.where(itf.on, q["p"], 0.0), "w": itf.w}
    return out


def ancf_points(psi: float, elements: int, mu: float, level: float, tmp: str, space: str | None,
                element: str | None = None) -> dict:
    """The same for the beams (solid_friction_profiles.ancf_contact; μ = 0: frictionless;
    ``element``: every beam's element, None the default)."""
    from ancf_verify.friction.profiles import ancf_contact
    name = f"across_{elements}_{mu:g}_{space}" + (f"_{element}" if element else "")
    out = os.path.join(tmp, name.replace(" ", "_"))
    pts = ancf_contact(psi, elements, mu, level, None, out, space, element=element)
    if pts is None:
        return {}
    itf, x0, p, area = pts["interface"], pts["x0"], pts["pressure"], pts["area"]
    return {name: {"x": x0[itf == i, 0], "P": untwist(x0[itf == i], psi), "p": p[itf == i], "w": area[itf == i]}
            for i, name in enumerate(IFACES)}


def binned_rows(pts: dict, frame: dict, centres, head: dict) -> list:
    """Rows per interface, window and across bin: weight Σw, Σ w p⁺, Σ w p⁻, the bin's mean s."""
    rows = []
    for name, d in pts.items():
        s = frame[name](d["P"])
        for xc in centres:
            m = np.abs(d["x"] - xc) < 0.5 * WINDOW
            lo = np.floor(s[m].min() / SBIN) if m.any() else 0
            k = np.floor(s[m] / SBIN) - lo
            for b in range(int(k.max()) + 1 if m.any() else 0):
                sel = k == b
                if not sel.any():
                    continue
                w, p = d["w"][m][sel], d["p"][m][sel]
                rows.append(head | {"interface": name, "x_c_m": xc, "s_lo_m": (lo + b) * SBIN,
                                    "s_hi_m": (lo + b + 1) * SBIN, "weight_m2": float(w.sum()),
                                    "force_plus_N": float((w * np.maximum(p, 0)).sum()),
                                    "force_minus_N": float((w * np.minimum(p, 0)).sum()),
                                    "s_centre_m": float((w * s[m][sel]).sum() / w.sum())})
    return rows


def read(path: str = CSV) -> list:
    return read_csv(path)


def write(rows: list, path: str = CSV) -> None:
    write_sci(path, FIELDS, rows)


def key(r: dict) -> tuple:
    """A run's rows share (model, variant, resolution)."""
    return (r["model"], r["variant"], r["resolution"])


def across_md(rows: list) -> list:
    """Per model and axial window, the mean compressive and tensile pressure Σ w p± / Σ w [kPa]
    of each interface (docs/solid_friction_across.csv, scripts/solid_friction_across.py)."""
    xs = sorted({num(r["x_c_m"]) for r in rows})
    keys = sorted(dict.fromkeys(key(r) for r in rows), key=lambda k: k[0] != SOLID)   # the solid first
    L = ["| model | variant | " + " | ".join(f"x = {1e3 * x:g} mm: " + " · ".join(IFACES) for x in xs) + " |",
         "|---|---|" + "---:|" * len(xs)]
    for k in keys:
        cells = []
        for x in xs:
            part = []
            for i in IFACES:
                sel = [r for r in rows if key(r) == k and r["interface"] == i and num(r["x_c_m"]) == x]
                w = sum(num(r["weight_m2"]) for r in sel)
                part.append("—" if not w else f"{1e-3 * sum(num(r['force_plus_N']) for r in sel) / w:.0f} / "
                            f"{1e-3 * sum(num(r['force_minus_N']) for r in sel) / w:.0f}")
            cells.append(" · ".join(part))
        L.append(f"| {k[0]} {k[2]} | {k[1]} | " + " | ".join(cells) + " |")
    return L


def plot(rows: list, path: str = PNG) -> None:
    """p̄(s) per interface (columns) and window (rows): the solid runs, the beams at the largest
    element count (every count is in the CSV and the table; the element rows: ``plot_orders``)."""
    plain = [r for r in rows if r["model"] in (SOLID, ANCF)]
    top = max((int(r["resolution"].split()[0]) for r in plain if r["model"] == ANCF), default=0)
    keys = [k for k in dict.fromkeys(key(r) for r in plain) if k[0] == SOLID or k[2] == f"{top} el."]

    def style(j, k):
        solid = k[0] == SOLID
        return {"color": ("k" if "2.00" in k[2] else "0.45") if solid else ("C3" if SPACE in k[1] else "C0"),
                "lw": 2.0 if solid else 1.0,
                "ls": "--" if k[1].startswith("mu 0,") or k[1] == "mu 0" else "-", "marker": None if solid else "."}
    draw(plain, keys, style, path, "solid black")


def plot_orders(rows: list, path: str = PNG_ORDERS, elements: int = 8) -> None:
    """The same for the section orders (issue 42): the solid runs with friction, the order-2 beams
    (ANCF) and every element row (model "ANCF <element> 2pt") at ``elements``, with friction."""
    fric = [r for r in rows if r["variant"].startswith("mu 0.3")]
    keys = [k for k in dict.fromkeys(key(r) for r in fric) if k[0] == SOLID or k[2] == f"{elements} el."]

    def style(j, k):
        if k[0] == SOLID:
            return {"color": "k" if "2.00" in k[2] else "0.45", "lw": 2.0, "ls": "-", "marker": None}
        return {"color": f"C{j}", "lw": 1.0, "ls": "-" if k[0] == ANCF else "-.", "marker": "."}
    draw(fric, keys, style, path, f"solid black/grey, beams {elements} el.")


def draw(rows: list, keys: list, style, path: str, legend: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    xs = sorted({float(r["x_c_m"]) for r in rows})
    fig, ax = plt.subplots(len(xs), len(IFACES), figsize=(12, 2.8 * len(xs)), squeeze=False)
    for j, k in enumerate(keys):
        sty = style(j, k)
        for a, x in enumerate(xs):
            for b, i in enumerate(IFACES):
                sel = sorted((r for r in rows if key(r) == k and r["interface"] == i and float(r["x_c_m"]) == x),
                             key=lambda r: float(r["s_lo_m"]))
                s = [1e3 * float(r["s_centre_m"]) for r in sel]
                p = [1e-6 * (float(r["force_plus_N"]) + float(r["force_minus_N"])) / float(r["weight_m2"]) for r in sel]
                ax[a, b].plot(s, p, label=f"{k[0]} {k[2]}, {k[1]}", **sty)
                ax[a, b].set_title(f"{i}, x = {1e3 * x:g} mm", fontsize=9)
                ax[a, b].axhline(0, color="0.6", lw=0.5)
                ax[a, b].grid(True, lw=0.3)
    for a in ax[-1]:
        a.set_xlabel("across the interface s [mm]")
    for a in ax[:, 0]:
        a.set_ylabel("mean pressure in the bin [MPa]")
    ax[0, 0].legend(fontsize=6)
    load = float(rows[0]["load_N"]) if rows else float("nan")
    fig.suptitle(f"Contact pressure across the interfaces at {load:g} N, ψ = 45° ({legend})", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    fig.savefig(path, dpi=110)
    plt.close(fig)
