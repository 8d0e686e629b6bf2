"""CSV rows of the contact comparison (docs/solid_contact.csv), the reference values and the beams' errors."""
from __future__ import annotations

import csv

import numpy as np

from ancf_verify.contact.tendon import SHORT, SOURCE
from ancf_verify.convergence import richardson


# ============================================================================================
# Reference values, CSV, report, figure
# ============================================================================================
CSV_FIELDS = ["psi_deg", "law", "model", "resolution", "h_m", "elements", "dofs", "load_N",
              "soleus_ux_m", "medial_ux_m", "lateral_ux_m", "soleus_face_ux_m", "uncertainty_rel",
              "wall_s", "newton_its", "gap_max_m", "multipliers", "kink_floor", "note"]

SOLID, ANCF, REF = "solid P2 tet", "ANCF 2pt", "solid reference (Richardson)"
#: the same solid with a pure penalty instead of exact multipliers (--penalty; a sensitivity study,
#: no reference is made of it); its resolution names ε
PENALTY = "solid P2 tet, penalty"


def resolution(run: dict) -> str:
    """A solid run's label: its mesh size, and ε of a pure penalty."""
    return f"h {run['h'] * 1e3:.2f} mm" + (f", penalty eps = {run['penalty']:g} mu/h" if run.get("penalty") else "")


def solid_rows(run: dict) -> list:
    rows = []
    for lv in run["levels"]:
        u = lv["u"]
        note = "" if run["ok"] else f"run stopped: {run['msg']}"
        if "p_min" in lv:
            note = (f"p [{lv['p_min'] / 1e6:+.3f}, {lv['p_max'] / 1e6:+.3f}] MPa; active {lv['active']}/{lv['nc']}; "
                    f"slave points past the master's edge {lv['off']}/{lv['nq']}" + ("; " + note if note else ""))
        rows.append({"psi_deg": run["psi"], "law": run["law"], "model": PENALTY if run.get("penalty") else SOLID,
                     "resolution": resolution(run), "h_m": run["h"], "elements": "",
                     "dofs": run["dofs"], "load_N": lv["load"],
                     "soleus_ux_m": u["soleus"][0], "medial_ux_m": u.get("medial", [np.nan])[0],
                     "lateral_ux_m": u.get("lateral", [np.nan])[0], "soleus_face_ux_m": lv["face"][0],
                     "uncertainty_rel": "", "wall_s": lv["wall"], "newton_its": lv["its"],
                     "gap_max_m": lv.get("g_max", ""), "multipliers": run["nc"],
                     "kink_floor": run["stats"].get("stalls", 0), "note": note})
    if not run["levels"] or not run["ok"]:
        rows.append({"psi_deg": run["psi"], "law": run["law"], "model": PENALTY if run.get("penalty") else SOLID,
                     "resolution": resolution(run), "h_m": run["h"], "dofs": run["dofs"],
                     "load_N": "", "note": f"FAILED: {run['msg']}"})
    return rows


def ancf_rows(run: dict) -> list:
    rows = []
    for lv in run["levels"]:
        u = lv["u"]
        rows.append({"psi_deg": run["psi"], "law": run["law"], "model": ANCF,
                     "resolution": f"{run['elements']} el.", "h_m": "", "elements": run["elements"],
                     "dofs": run["dofs"], "load_N": lv["load"], "soleus_ux_m": u["soleus"][0],
                     "medial_ux_m": u["medial"][0] if "medial" in u else np.nan,
                     "lateral_ux_m": u["lateral"][0] if "lateral" in u else np.nan, "soleus_face_ux_m": "",
                     "uncertainty_rel": "", "wall_s": run["wall"], "newton_its": lv["its"], "gap_max_m": "",
                     "note": f"ancf_petsc of {SOURCE.label}"})
    if not run["ok"]:
        rows.append({"psi_deg": run["psi"], "law": run["law"], "model": ANCF,
                     "resolution": f"{run['elements']} el.", "elements": run["elements"], "dofs": run["dofs"],
                     "load_N": "", "wall_s": run["wall"], "note": f"FAILED: {run['msg']}"})
    return rows


def num(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return float("nan")


def reference_rows(rows: list) -> list:
    """Richardson extrapolation (verify_solid.richardson: finest three meshes, h ~ DOFs^-1/3,
    fitted order; or the finest mesh with its last change) per (psi, law, load) for each of the
    four quantities; the soleus end-centroid's uncertainty in ``uncertainty_rel``."""
    out = []
    keys = sorted({(num(r["psi_deg"]), r["law"]) for r in rows if r["model"] == SOLID})
    for psi, law in keys:
        fam = [r for r in rows if r["model"] == SOLID and num(r["psi_deg"]) == psi and r["law"] == law
               and r["load_N"] not in ("", None)]
        hs = sorted({num(r["h_m"]) for r in fam}, reverse=True)
        loads = sorted({num(r["load_N"]) for r in fam})
        for F in loads:
            per_h = []
            for h in hs:
                r = [x for x in fam if num(x["h_m"]) == h and num(x["load_N"]) == F]
                if r:
                    per_h.append(r[0])
            if len(per_h) < 2 or len(per_h) < len(hs):
                continue
            rec = {"psi_deg": psi, "law": law, "model": REF, "resolution": "", "h_m": "", "elements": "",
                   "dofs": "", "load_N": F, "wall_s": "", "newton_its": "", "gap_max_m": ""}
            notes = []
            for q in ("soleus_ux_m", "medial_ux_m", "lateral_ux_m", "soleus_face_ux_m"):
                vals = [num(r[q]) for r in per_h]
                if not np.all(np.isfinite(vals)):
                    rec[q] = ""
                    continue
                solids = [{"u": np.array([v]), "dofs": int(num(r["dofs"]))} for v, r in zip(vals, per_h)]
                if len(solids) >= 3:
                    ref, unc, how = richardson(solids)
                    if how.startswith("finest mesh"):
                        # not monotone: the finest mesh, and (conservatively) its largest
                        # difference to any coarser mesh as the uncertainty
                        unc = max(abs(v - vals[-1]) for v in vals[:-1]) / abs(vals[-1])
                        how = ("finest mesh (changes not monotone); uncertainty: its largest difference "
                               "to a coarser mesh")
                else:   # two meshes: the finer, with the last change as its uncertainty
                    ref = solids[-1]["u"]
                    unc = float(abs(vals[-1] - vals[-2]) / abs(vals[-1]))
                    how = "finest of two meshes, the last change as the uncertainty"
                rec[q] = float(ref[0])
                if q == "soleus_ux_m":
                    rec["uncertainty_rel"] = unc
                    notes.append(how)
            rec["resolution"] = f"{len(per_h)} meshes, h {1e3 * hs[0]:.2f}-{1e3 * hs[-1]:.2f} mm"
            rec["note"] = "; ".join(notes)
            out.append(rec)
    return out


def write_rows(path: str, fields: tuple, rows: list, precise) -> None:
    """``rows`` as CSV with the columns ``fields``: floats with 11 digits where ``precise(field)``,
    6 elsewhere, empty where not finite."""
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            d = {}
            for k in fields:
                v = r.get(k, "")
                if isinstance(v, (float, np.floating)):
                    v = "" if not np.isfinite(v) else (f"{v:.10e}" if precise(k) else f"{v:.6g}")
                d[k] = v
            w.writerow(d)


def write_csv(path: str, rows: list) -> None:
    write_rows(path, CSV_FIELDS, rows, lambda k: k.endswith("_m") or k == "uncertainty_rel")


def read_csv(path: str) -> list:
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


def ancf_errors(rows: list) -> dict:
    """Relative error of the ANCF soleus elongation against the solid reference, per (psi, law,
    elements): worst over the loads, at 10 N and at 400 N (NaN where missing)."""
    refs = {(num(r["psi_deg"]), r["law"], num(r["load_N"])): r for r in rows if r["model"] == REF}
    out = {}
    for r in rows:
        if r["model"] != ANCF or r["load_N"] in ("", None):
            continue
        ref = refs.get((num(r["psi_deg"]), r["law"], num(r["load_N"])))
        if ref is None:
            continue
        e = (num(r["soleus_ux_m"]) - num(ref["soleus_ux_m"])) / num(ref["soleus_ux_m"])
        d = out.setdefault((r["psi_deg"], r["law"], int(num(r["elements"]))), {})
        d[num(r["load_N"])] = e
    return out


def ref_loads(rows: list, psi, law) -> set:
    """The load levels [N] at which the solid reference of (psi, law) exists."""
    return {num(r["load_N"]) for r in rows if r["model"] == REF and num(r["psi_deg"]) == num(psi)
            and r["law"] == law}


def check_row(name: str, value: float, text: str, psi="", law="") -> dict:
    """A verification result as a CSV row (model 'check'): the number in uncertainty_rel."""
    return {"psi_deg": psi, "law": law, "model": "check", "resolution": name, "uncertainty_rel": value,
            "note": text}


def selftest_rows(st: dict) -> list:
    rows = []
    s = st["single"]
    worst = max(s[b]["rel"] for b in SHORT)
    rows.append(check_row("single bodies vs verify_solid", worst,
                          "contact off, the three bodies of one mesh each pulled by 20 N at its end (psi 45, h 3 mm), "
                          "against verify_solid.solve_solid on each body meshed alone with its unstructured mesh: "
                          + "; ".join(f"{b} {1e3 * s[b]['mine'][0]:.5f} vs {1e3 * s[b]['ref'][0]:.5f} mm "
                                      f"(|du|/|u| {s[b]['rel']:.2e})" for b in SHORT)))
    for r in st["blocks"]:
        rows.append(check_row(f"patch {r['kind']} {r['law']}", r["err"],
                              f"two blocks, flat interface, non-matching meshes (h {r['h'][1] * 1e3:.2f}/"
                              f"{r['h'][0] * 1e3:.2f} mm), relative slide {r['slide'] * 1e3:.3f} mm: max nodal "
                              f"|u - u_exact|/max|u_exact| {r['err']:.2e}; pointwise |g - g0| max {r['g_max']:.1e} m; "
                              f"pressure [{r['p_min'] / 1e6:+.5f}, {r['p_max'] / 1e6:+.5f}] MPa (exact "
                              f"{r['p_exact'] / 1e6:+.5f}); active {r['active']}/{r['nc']}; {r['its']} Newton its"))
    for r in st["fd"]:
        e = min(r[k]["full"] for k in (1e-5, 1e-6, 1e-7))
        rows.append(check_row(f"finite differences {r['law']}", e,
                              f"tendon psi 45 deg, h {r['h'] * 1e3:g} mm ({r['ndof']} DOFs, {r['nc']} multipliers), "
                              "deformed state with 2 mm of sliding; |FD - J d|/|J d| at eps = 1e-5/1e-6/1e-7 h: "
                              "full system " + "/".join(f"{r[k]['full']:.1e}" for k in (1e-5, 1e-6, 1e-7))
                              + ", weighted gaps " + "/".join(f"{r[k]['gbar']:.1e}" for k in (1e-5, 1e-6, 1e-7))
                              + ", contact forces " + "/".join(f"{r[k]['contact_force']:.1e}" for k in (1e-5, 1e-6, 1e-7))
                              + f"; without the gap Hessian the tangent is off by {r['no_geo_full']:.1e} of |J d|"))
    return rows


def independence_rows(base: dict, other: dict, label: str) -> list:
    """Largest relative difference of the four end quantities between two runs (same mesh)."""
    worst, where = 0.0, ""
    for a, b in zip(base["levels"], other["levels"]):
        for q in a["u"]:
            d = abs(a["u"][q][0] - b["u"][q][0]) / abs(a["u"]["soleus"][0])
            if d > worst:
                worst, where = d, f"{q} at {a['load']:g} N"
    n = min(len(base["levels"]), len(other["levels"]))
    ok = base["ok"] and other["ok"]
    return [check_row(f"independence {label}", worst,
                      f"{label}: largest difference of the end-centroid u_x (relative to the soleus') over "
                      f"{n} load levels {worst:.1e} ({where}); h {base['h'] * 1e3:.2f} mm"
                      + ("" if ok else "; a run did not complete"), base["psi"], base["law"])]


def row_key(r: dict) -> tuple:
    """Rows of one run (or one check) share this key; --merge replaces them as a whole."""
    if r["model"] == "check":
        return ("check", r["resolution"])
    return (r["model"], num(r["psi_deg"]), r["law"], r["resolution"])


def mesh_changes(rows: list) -> dict:
    """Per (law, psi): the largest relative change of the soleus elongation over the loads between
    the two finest meshes, and the largest reference uncertainty."""
    out = {}
    solids = [r for r in rows if r["model"] == SOLID and r["load_N"] not in ("", None)]
    for law, psi in sorted({(r["law"], num(r["psi_deg"])) for r in solids}):
        fam = [r for r in solids if r["law"] == law and num(r["psi_deg"]) == psi]
        hs = sorted({num(r["h_m"]) for r in fam})
        if len(hs) < 2:
            continue
        u = {(num(r["h_m"]), num(r["load_N"])): num(r["soleus_ux_m"]) for r in fam}
        ch = [abs(u[(hs[0], F)] - u[(hs[1], F)]) / abs(u[(hs[0], F)]) for (h, F) in u if h == hs[0] and (hs[1], F) in u]
        unc = [num(r["uncertainty_rel"]) for r in rows if r["model"] == REF and r["law"] == law
               and num(r["psi_deg"]) == psi]
        out[(law, psi)] = {"change": max(ch) if ch else float("nan"), "unc": max(unc) if unc else float("nan"),
                           "h": hs[:2], "hows": sorted({r["note"] for r in rows if r["model"] == REF
                                                        and r["law"] == law and num(r["psi_deg"]) == psi})}
    return out
