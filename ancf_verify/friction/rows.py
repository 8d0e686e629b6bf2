"""CSV rows and reference values of the friction comparison (docs/solid_friction.csv)."""
from __future__ import annotations

from dataclasses import dataclass
import csv
import os

import numpy as np

from ancf_verify.contact.rows import write_rows


SOLID, ANCF, CHECK = "solid P2 tet", "ANCF 2pt", "check"

BASE = "stick 100"                   # the solid's reference variant

ZONE = ", no friction x < "          # a free-zone diagnostic's variant: "<variant>, no friction x < 10 mm"

SPACE = ", pressure "                # a pressure-space variant: "<variant>, pressure quadratic across"

LOCAL = " mm at "                    # a locally refined mesh's resolution: "h 2.00 mm, 0.70 mm at mg_sol"


#: the beams' contact pressure (and tangential multiplier) spaces beside the default (linear along
#: x linear across under friction since 2026-12-07, quadratic along before; 3 x 2 points): name ->
#: contact keys (docs/solid_contact.md's variants)
SPACES = {"quadratic across": {"curve_points": 3, "projection": {"axial": 2, "curve": 2}},
          "cubic along": {"axial_points": 4, "projection": {"axial": 3, "curve": 1}},
          "cubic across": {"curve_points": 4, "projection": {"axial": 2, "curve": 3}}}

DEFAULT_SPACE = "linear along × linear across"


def ancf_model(element: str | None = None) -> str:
    """The model label of an ANCF column: ANCF for the config's own element (none set: 3363), and
    with the element named when one is set (``--element``), e.g. "ANCF 33103 2pt"; the page's
    generated tables read the ANCF rows only, the element rows are issue 42's (friction.orders)."""
    return ANCF if not element else ANCF.replace("ANCF", f"ANCF {element}", 1)


IFACES = ("mg_sol", "lg_sol", "lg_mg")

BODIES = ("soleus", "medial", "lateral")

FIELDS = (["psi_deg", "mu", "model", "variant", "resolution", "h_m", "elements", "dofs", "load_N"]
          + [f"{b}_ux_m" for b in BODIES] + [f"fx_{i}_N" for i in IFACES] + [f"stick_{i}" for i in IFACES]
          + ["p_max_Pa", "p_min_Pa", "newton_its", "wall_s", "value", "note"])

BEGIN = "<!-- verify_solid_friction: begin (generated from docs/solid_friction.csv; do not edit) -->"

END = "<!-- verify_solid_friction: end -->"


@dataclass
class Paths:
    out: str

    @property
    def csv(self) -> str:
        return os.path.join(self.out, "solid_friction.csv")

    @property
    def md(self) -> str:
        return os.path.join(self.out, "interface.md")

    @property
    def png(self) -> str:
        return os.path.join(self.out, "figures", "solid_friction.png")


def num(x) -> float:
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")


def read_csv(path: str) -> list:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def write_csv(path: str, rows: list) -> None:
    write_rows(path, FIELDS, rows, lambda k: k.endswith(("_m", "_N", "_Pa")) or k == "value")


def write_sci(path: str, fields, rows: list) -> None:
    """``rows`` as CSV with the columns ``fields`` (keys outside them dropped), floats as %.6e, None
    empty: the friction profiles, the pressure across and the inf-sup constants."""
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6e}" if isinstance(v, float) else v) for k, v in r.items() if k in fields})


def row_key(r: dict) -> tuple:
    """Rows of one run (or one check) share this key; a new run replaces them as a whole."""
    if r["model"] == CHECK:
        return (CHECK, r["variant"], r["resolution"])
    return (r["model"], num(r["psi_deg"]), num(r["mu"]), r["variant"], r["resolution"])


# ============================================================================================
# Rows
# ============================================================================================
def solid_rows(run: dict, psi: float, mu: float, variant: str) -> list:
    rows = []
    res = f"h {run['h'] * 1e3:.2f} mm" + (f", {run['local'].label()}" if run.get("local") else "")
    for lv in run["levels"]:
        fr = lv.get("friction", {})
        r = {"psi_deg": psi, "mu": mu, "model": SOLID, "variant": variant, "resolution": res, "h_m": run["h"],
             "dofs": run["dofs"], "load_N": lv["load"], "newton_its": lv["its"], "wall_s": lv["wall"],
             "p_max_Pa": lv.get("p_max", np.nan), "p_min_Pa": lv.get("p_min", np.nan),
             "note": f"kink floor {run['stats'].get('stalls', 0)}"}
        for b in BODIES:
            r[f"{b}_ux_m"] = float(lv["u"][b][0])
        for i in IFACES:
            r[f"fx_{i}_N"] = fr.get(i, {}).get("force_x", np.nan)
            r[f"stick_{i}"] = fr.get(i, {}).get("stick_share", np.nan)
        rows.append(r)
    if not run["ok"]:
        rows.append({"psi_deg": psi, "mu": mu, "model": SOLID, "variant": variant, "resolution": res,
                     "h_m": run["h"], "dofs": run["dofs"], "note": f"FAILED: {run['msg']}"})
    return rows


def ancf_variant(aug: float | None, space: str | None = None) -> str:
    """The ANCF variant label of the Coulomb law's augmentation factor c (None: the default) and
    of the pressure space (a SPACES name; None: the default)."""
    return ("augmentation default" if aug is None else f"augmentation {aug:.3g}") + (f"{SPACE}{space}" if space else "")


def variant_value(variant: str) -> str:
    """The augmentation's value alone (before the space and free-zone suffixes): 'default', '10', ..."""
    return variant.split(ZONE)[0].split(SPACE)[0].split()[-1]


def variant_space(variant: str) -> str:
    """The pressure space of a variant (a SPACES name, or DEFAULT_SPACE)."""
    head = variant.split(ZONE)[0]
    return head.split(SPACE)[1] if SPACE in head else DEFAULT_SPACE


def ancf_rows(run: dict, mu: float) -> list:
    rows = []
    variant = ancf_variant(run["augmentation"], run.get("space"))
    if run.get("zone"):
        variant += f"{ZONE}{run['zone'] * 1e3:g} mm"
    res = f"{run['elements']} el."
    model = ancf_model(run.get("element"))
    for lv in run["levels"]:
        fr = lv["friction"]
        r = {"psi_deg": run["psi"], "mu": mu, "model": model, "variant": variant, "resolution": res,
             "elements": run["elements"], "dofs": run["dofs"], "load_N": lv["load"], "newton_its": lv["its"],
             "wall_s": run["wall"], "p_max_Pa": max(fr.get(i + "_pmax", np.nan) for i in IFACES)}
        for b in BODIES:
            r[f"{b}_ux_m"] = float(lv["u"][b])
        for i in IFACES:
            # the x-force on the solid's slave body (medial, lateral, medial); the beams report the
            # force of the first beam in config order on the second (soleus|medial,
            # soleus|lateral, medial|lateral): the slave is the second on mg_sol and lg_sol
            r[f"fx_{i}_N"] = (-1.0 if i == "lg_mg" else 1.0) * fr.get(i, np.nan)
            r[f"stick_{i}"] = fr.get(i + "_stick", np.nan)
        rows.append(r)
    if not run["ok"]:
        rows.append({"psi_deg": run["psi"], "mu": mu, "model": model, "variant": variant, "resolution": res,
                     "elements": run["elements"], "dofs": run["dofs"], "wall_s": run["wall"],
                     "note": f"FAILED: {run['msg']}"})
    return rows


def fd_rows(recs: list) -> list:
    out = []
    for r in recs:
        best = min(r[e]["full"] for e in (1e-5, 1e-6, 1e-7, 1e-8))
        text = (f"tendon psi 45 deg, h {r['h'] * 1e3:g} mm ({r['ndof']} DOFs, {r['nq']} slave points: {r['stick']} "
                f"stick, {r['slide']} slip), 2 mm of sliding; |FD - J d|/|J d| at eps = 1e-5/1e-6/1e-7/1e-8 h: full "
                + "/".join(f"{r[e]['full']:.1e}" for e in (1e-5, 1e-6, 1e-7, 1e-8)) + ", friction forces "
                + "/".join(f"{r[e]['friction']:.1e}" for e in (1e-5, 1e-6, 1e-7, 1e-8))
                + "; stick/slip set unchanged within +-eps: " + "/".join("yes" if r[e]["same"] else "no"
                                                                       for e in (1e-5, 1e-6, 1e-7, 1e-8)))
        out.append({"model": CHECK, "variant": f"finite differences, slip {r['slip']}", "resolution": "",
                    "value": best, "note": text})
    return out


# ============================================================================================
# Reference and errors
# ============================================================================================
def solid_runs(rows: list, psi: float, variant: str = BASE) -> dict:
    """{h: {load: row}} of the solid runs of one variant at ψ on uniform meshes (the locally
    refined ones: friction.refined)."""
    out = {}
    for r in rows:
        if (r["model"] == SOLID and r["variant"] == variant and num(r["psi_deg"]) == psi and r["load_N"]
                and LOCAL not in r["resolution"]):
            out.setdefault(num(r["h_m"]), {})[num(r["load_N"])] = r
    return out


def reference(rows: list, psi: float) -> dict:
    """{load: {body: (u_ref, mesh change)}}: the finest mesh of the base variant, its change
    from the next coarser mesh as the uncertainty."""
    runs = solid_runs(rows, psi)
    if not runs:
        return {}
    hs = sorted(runs)
    fine, coarse = runs[hs[0]], runs[hs[1]] if len(hs) > 1 else {}
    out = {}
    for F, r in fine.items():
        out[F] = {b: (num(r[f"{b}_ux_m"]), abs(num(r[f"{b}_ux_m"]) - num(coarse[F][f"{b}_ux_m"]))
                      if F in coarse else float("nan")) for b in BODIES}
        out[F]["row"] = r
    return out


def differences(a: dict, b: dict) -> dict:
    """Worst over the common loads of |Δu_b|/u_soleus and |Δu_b|/|u_b| between two runs
    {load: row} (b's values as the reference)."""
    common = sorted(set(a) & set(b))
    out = {"loads": common}
    for body in BODIES:
        d = [abs(num(a[F][f"{body}_ux_m"]) - num(b[F][f"{body}_ux_m"])) for F in common]
        us = [abs(num(b[F]["soleus_ux_m"])) for F in common]
        ub = [abs(num(b[F][f"{body}_ux_m"])) for F in common]
        out[body + "_abs"] = max((x / y for x, y in zip(d, us)), default=float("nan"))
        out[body + "_rel"] = max((x / y for x, y in zip(d, ub)), default=float("nan"))
    return out


def ancf_columns(rows: list, psi: float, zone: bool = False) -> dict:
    """{(variant, elements): {"levels": {load: row}, "failed": note or ""}} of the plain columns
    (``zone``: of the free-zone diagnostics instead)."""
    out = {}
    for r in rows:
        if r["model"] != ANCF or num(r["psi_deg"]) != psi or (ZONE in r["variant"]) != zone:
            continue
        col = out.setdefault((r["variant"], int(num(r["elements"]))), {"levels": {}, "failed": ""})
        if r["load_N"]:
            col["levels"][num(r["load_N"])] = r
        else:
            col["failed"] = r["note"]
    return out


def errors(levels: dict, ref: dict) -> dict:
    """{load: {body: (relative, against the soleus elongation)}} of a column {load: row} against
    a solid run {load: row}, at the loads both have."""
    e = {}
    for F, r in levels.items():
        if F not in ref:
            continue
        us = abs(num(ref[F]["soleus_ux_m"]))
        e[F] = {b: ((num(r[f"{b}_ux_m"]) - num(ref[F][f"{b}_ux_m"])) / abs(num(ref[F][f"{b}_ux_m"])),
                    (num(r[f"{b}_ux_m"]) - num(ref[F][f"{b}_ux_m"])) / us) for b in BODIES}
    return e


def ancf_errors(rows: list, psi: float) -> dict:
    """Per ANCF column: the errors against the reference at every reached level,
    {(variant, elements): {load: {body: (relative, against the soleus elongation)}}}."""
    ref = {F: v["row"] for F, v in reference(rows, psi).items()}
    return {key: errors(col["levels"], ref) for key, col in ancf_columns(rows, psi).items()}


def stick_order(variant: str) -> tuple:
    """Sort key of the ANCF variants: the default space first, then augmentation default, then
    large to small."""
    word, space = variant_value(variant), variant_space(variant)
    rank = 0 if space == DEFAULT_SPACE else 1 + list(SPACES).index(space) if space in SPACES else 9
    return (rank, 0, 0.0) if word == "default" else (rank, 1, -num(word))
