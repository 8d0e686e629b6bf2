"""One table of every 3D-solid reference: its meshes, its mesh convergence and the beams' error
against it at 2 / 4 / 8 / 16 elements, read from the committed CSVs in docs/ (nothing solved)."""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field

import numpy as np

from ancf_verify.paths import DOCS

ELEMENTS = (2, 4, 8, 16)


@dataclass
class Reference:
    """One row: a solid reference, how converged it is, the beams' relative error per element count."""
    name: str
    quantity: str
    meshes: str
    convergence: float                    # relative uncertainty of the reference (mesh change)
    errors: dict = field(default_factory=dict)   # elements → relative error (worst over loads)
    source: str = ""
    signed: bool = True                   # False: a norm |Δu|/|u| (no sign to print)


def _worst(values) -> float:
    vals = [v for v in values if np.isfinite(v)]
    return max(vals, key=abs) if vals else math.nan


def bars(docs: str = DOCS) -> list[Reference]:
    """docs/solid_comparison.csv: the end-centroid displacement of the four bars (2 axial points)."""
    from ancf_verify.contact.rows import read_csv
    rows = read_csv(os.path.join(docs, "solid_comparison.csv"))
    out = []
    for case in dict.fromkeys(r["case"] for r in rows):
        mine = [r for r in rows if r["case"] == case]
        solid = [r for r in mine if r["model"].startswith("solid")]
        errs = {int(r["resolution"].split()[0]): float(r["rel_error"]) for r in mine if r["model"] == "ANCF 2pt"}
        out.append(Reference(f"bar: {case}", "|Δu|/|u| end centroid", f"{len(solid)} meshes, h {solid[0]['resolution'][2:]}"
                             f"-{solid[-1]['resolution'][2:]}", float(mine[0]["ref_rel_uncertainty"]),
                             {n: errs.get(n, math.nan) for n in ELEMENTS}, "solid_comparison.csv", signed=False))
    return out


def contact(docs: str = DOCS, name: str = "solid_contact.csv", roots: str = "clamped") -> list[Reference]:
    """docs/solid_contact.csv: the soleus elongation of the three subtendons (worst over the loads);
    ``name``, ``roots``: another CSV of the same study and its roots (solid_contact_plane.csv)."""
    from ancf_verify.contact.rows import REF, ancf_errors, num, read_csv
    rows = read_csv(os.path.join(docs, name))
    errs = ancf_errors(rows)
    out = []
    for psi, law in dict.fromkeys((r["psi_deg"], r["law"]) for r in rows if r["model"] == REF):
        refs = [r for r in rows if r["model"] == REF and (r["psi_deg"], r["law"]) == (psi, law)]
        e = {n: _worst(errs.get((psi, law, n), {}).values()) for n in ELEMENTS}
        out.append(Reference(f"three subtendons, {law}, ψ = {num(psi):g}°, {roots} roots",
                             "soleus u_x, worst over loads", refs[0]["resolution"],
                             max(num(r["uncertainty_rel"]) for r in refs), e, name))
    return out


def contact_plane(docs: str = DOCS) -> list[Reference]:
    """docs/solid_contact_plane.csv: the same on roots that slide on a frictionless plane."""
    return contact(docs, "solid_contact_plane.csv", "plane")


def friction(docs: str = DOCS, psi: float = 45.0) -> list[Reference]:
    """docs/solid_friction.csv: the soleus elongation with Coulomb friction μ = 0.3 (default beams)."""
    from ancf_verify.friction.rows import ancf_errors, ancf_variant, read_csv, reference, solid_runs
    rows = read_csv(os.path.join(docs, "solid_friction.csv"))
    ref = reference(rows, psi)
    if not ref:
        return []
    hs = sorted(solid_runs(rows, psi))
    conv = max(v["soleus"][1] / abs(v["soleus"][0]) for v in ref.values())
    errs = ancf_errors(rows, psi)
    e = {n: _worst(lv["soleus"][0] for lv in errs.get((ancf_variant(None), n), {}).values()) for n in ELEMENTS}
    return [Reference(f"three subtendons, Coulomb μ = 0.3, ψ = {psi:g}°", "soleus u_x, worst over loads",
                      f"{len(hs)} meshes, h {1e3 * hs[-1]:.2f}-{1e3 * hs[0]:.2f} mm", conv, e, "solid_friction.csv")]


def fibres(docs: str = DOCS) -> list[Reference]:
    """docs/solid_fibres.csv: the end displacement of the helical-fibre bar (plain beams)."""
    from ancf_verify.fibres.report import read_csv, runs_of
    out = []
    for key, c in runs_of(read_csv(os.path.join(docs, "solid_fibres.csv"))).items():
        e = {int(r["res"].split()[0]): r["err_u"] for r in c["ancf"]}
        out.append(Reference(f"fibre bar: {c['law']}, K/μ = {c['ratio']:g}", "|Δu|/|u| end centroid", f"{len(c['solid'])} meshes, "
                             f"{c['solid'][0]['res'][2:]}-{c['solid'][-1]['res'][2:]}", c["unc_u"],
                             {n: e.get(n, math.nan) for n in ELEMENTS}, "solid_fibres.csv", signed=False))
    return out


def soft_matrix(docs: str = DOCS) -> list[Reference]:
    """docs/solid_soft_matrix.csv: the soft-matrix bar's end u_x (beams with the end traction)."""
    from ancf_verify.fibres.report import read_csv
    from ancf_verify.soft_matrix.cases import model_name
    from ancf_verify.soft_matrix.solid import evaluate
    ev = evaluate(read_csv(os.path.join(docs, "solid_soft_matrix.csv")))
    solid, out = ev["solid"], []
    for locking in ("none", "mixed"):
        name = model_name(locking, "traction_force")
        e = {int(r["res"].split()[0]): r["du"] for r in ev["beam"] if r["model"] == name}
        out.append(Reference(f"soft-matrix bar (GOH alex set), beams locking: {locking}", "u_x end centroid",
                             f"{len(solid)} meshes, {solid[0]['res'][2:]}-{solid[-1]['res'][2:]}", ev["unc_u"],
                             {n: e.get(n, math.nan) for n in ELEMENTS}, "solid_soft_matrix.csv"))
    return out


FAMILIES = (bars, contact, contact_plane, friction, fibres, soft_matrix)


def references(docs: str = DOCS) -> list[Reference]:
    """Every reference of the committed CSVs (a family whose CSV is missing is left out)."""
    out = []
    for family in FAMILIES:
        try:
            out += family(docs)
        except FileNotFoundError:
            continue
    return out


def _pct(x: float, signed: bool = True) -> str:
    return "—" if not np.isfinite(x) else f"{100 * x:+.2f} %" if signed else f"{100 * x:.2f} %"


def table(refs: list[Reference]) -> str:
    """The markdown table: reference, quantity, meshes, mesh convergence, beam errors."""
    lines = ["| reference | quantity | solid meshes | mesh convergence | "
             + " | ".join(f"beams {n} el." for n in ELEMENTS) + " |",
             "|---|---|---|---:|" + "---:|" * len(ELEMENTS)]
    for r in refs:
        conv = "—" if not np.isfinite(r.convergence) else f"{100 * r.convergence:.2f} %"
        lines.append(f"| {r.name} | {r.quantity} | {r.meshes} | {conv} | "
                     + " | ".join(_pct(r.errors.get(n, math.nan), r.signed) for n in ELEMENTS) + " |")
    return "\n".join(lines)
