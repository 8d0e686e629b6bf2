"""The page docs/solid_contact.md and its figure, made from the CSV alone."""
from __future__ import annotations

import os

import numpy as np

from ancf_verify.contact.rows import ANCF, REF, SOLID, ancf_errors, mesh_changes, num, ref_loads
from ancf_verify.paths import ROOT


def plot(path: str, rows: list) -> None:
    """Signed relative error of the ANCF soleus elongation against the solid reference, per ψ:
    worst over the loads, at 10 N and at 400 N, with the ±0.3 % target band and the reference's
    uncertainty."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    errs = ancf_errors(rows)
    psis = sorted({k[0] for k in errs}, key=num)
    laws = [l for l in ("sliding", "unilateral", "free") if any(k[1] == l for k in errs)]
    if not psis:
        return
    fig, axes = plt.subplots(1, len(psis), figsize=(4.6 * len(psis), 4.2), squeeze=False, sharey=True)
    style = {"sliding": ("C0", "o"), "unilateral": ("C1", "s"), "free": ("C2", "^")}
    handles = {}
    for ax, psi in zip(axes[0], psis):
        ax.axhspan(-0.3, 0.3, color="0.92", zorder=0)
        ax.axhline(0.0, color="0.5", lw=0.6)
        for law in laws:
            col, mk = style[law]
            ks = sorted(k for k in errs if k[0] == psi and k[1] == law)
            if not ks:
                continue
            nref = len(ref_loads(rows, psi, law))
            n = [k[2] for k in ks]
            worst = [100 * max(errs[k].values(), key=abs) if len(errs[k]) == nref else np.nan for k in ks]
            e10 = [100 * errs[k].get(10.0, np.nan) for k in ks]
            e400 = [100 * errs[k].get(400.0, np.nan) for k in ks]
            h1, = ax.plot(n, worst, "-", marker=mk, color=col, ms=6)
            h2, = ax.plot(n, e10, "--", marker=mk, color=col, mfc="none", ms=5)
            h3, = ax.plot(n, e400, ":", marker=mk, color=col, mfc="none", ms=5)
            handles[f"{law}: worst over the loads"] = h1
            handles[f"{law}: 10 N"] = h2
            handles[f"{law}: 400 N"] = h3
            unc = [num(x["uncertainty_rel"]) for x in rows if x["model"] == REF and num(x["psi_deg"]) == num(psi)
                   and x["law"] == law]
            if unc and np.isfinite(max(unc)):
                u = 100 * max(unc)
                ax.fill_between([1.8, 18], [-u, -u], [u, u], color=col, alpha=0.10, lw=0)
        ax.set_xscale("log", base=2)
        ax.set_xlim(1.8, 18)
        ax.set_xticks([2, 4, 8, 16])
        ax.set_xticklabels(["2", "4", "8", "16"])
        ax.set_title(f"psi = {num(psi):g} deg")
        ax.set_xlabel("ANCF elements per subtendon")
        ax.grid(True, which="both", lw=0.3, alpha=0.6)
    axes[0][0].set_ylabel("ANCF error of the soleus elongation [%]")
    fig.legend(list(handles.values()), list(handles.keys()), loc="lower center", ncol=3, fontsize=7.5,
               frameon=False)
    fig.suptitle("ANCF (2 axial points) against the 3D solid reference; grey: the +-0.3 % target, "
                 "tinted: +- the reference's uncertainty", fontsize=9.5)
    fig.tight_layout(rect=(0, 0.14, 1, 0.95))
    fig.savefig(path, dpi=130)
    plt.close(fig)


def limits_md(rows: list, errs: dict) -> str:
    """What limits the agreement, from the rows: the free soleus' error (beam kinematics of the
    loaded body alone) against the bundle's (the contact coupling on top), and the unilateral
    law against the sliding one at the lowest load (how much the soleus gains by separating)."""
    L = []
    psis = sorted({num(k[0]) for k in errs})
    pairs = []
    for psi in psis:
        for ne in sorted({k[2] for k in errs if num(k[0]) == psi}):
            f = [errs[k] for k in errs if num(k[0]) == psi and k[1] == "free" and k[2] == ne]
            sl = [errs[k] for k in errs if num(k[0]) == psi and k[1] == "sliding" and k[2] == ne]
            if f and sl:
                common = sorted(set(f[0]) & set(sl[0]))
                if common:
                    pairs.append((psi, ne, max((f[0][F] for F in common), key=abs),
                                  max((sl[0][F] for F in common), key=abs)))
    if pairs:
        L.append("### Beam kinematics or contact coupling\n")
        L.append("The same comparison for the soleus alone (no neighbours, same clamp and load) separates "
                 "what the 3363 beam makes of the loaded body from what the contact coupling adds.  Worst "
                 "signed error over the common loads:\n")
        L.append("| ψ | elements | soleus alone | three subtendons, sliding | difference |")
        L.append("|---:|---:|---:|---:|---:|")
        for psi, ne, ef, es in pairs:
            L.append(f"| {psi:g}° | {ne} | {fmt_pct(ef)} | {fmt_pct(es)} | {fmt_pct(es - ef)} |")
        L.append("")
    # unilateral against sliding at the lowest common load
    uni = [r for r in rows if r["law"] == "unilateral" and r["model"] in (REF, ANCF) and r["load_N"] not in ("", None)]
    if uni:
        L.append("### Separation at low load (unilateral against sliding)\n")
        L.append("(u_unilateral − u_sliding)/u_sliding of the soleus elongation: how much the soleus gains by "
                 "being free to lift off its neighbours.\n")
        L.append("| ψ | model | load [N] | sliding [mm] | unilateral [mm] | gain |")
        L.append("|---:|---|---:|---:|---:|---:|")
        for r in sorted(uni, key=lambda r: (num(r["psi_deg"]), r["model"] != REF, num(r["elements"] or 0),
                                            num(r["load_N"]))):
            if num(r["load_N"]) > 40.0:
                continue
            s = [x for x in rows if x["law"] == "sliding" and x["model"] == r["model"]
                 and num(x["psi_deg"]) == num(r["psi_deg"]) and num(x["load_N"]) == num(r["load_N"])
                 and (r["model"] == REF or x["elements"] == r["elements"])]
            if not s:
                continue
            us, uu = num(s[0]["soleus_ux_m"]), num(r["soleus_ux_m"])
            name = "solid reference" if r["model"] == REF else f"ANCF {r['elements']} el."
            L.append(f"| {num(r['psi_deg']):g}° | {name} | {num(r['load_N']):g} | {1e3 * us:.5f} | {1e3 * uu:.5f} | "
                     f"{fmt_pct((uu - us) / us, 2)} |")
        L.append("")
    return "\n".join(L)


def summary_md(rows: list, target: float = 0.003) -> str:
    """Summary sentences computed from the rows: mesh convergence and the ANCF errors."""
    L = ["## Summary (computed from the CSV)\n"]
    mc = mesh_changes(rows)
    for (law, psi), m in mc.items():
        L.append(f"* Solid, {law}, ψ = {psi:g}°: the soleus elongation changes by at most {100 * m['change']:.3f} % "
                 f"between h = {1e3 * m['h'][1]:.2f} and {1e3 * m['h'][0]:.2f} mm (over the loads); the reference's "
                 f"uncertainty is at most {100 * m['unc']:.3f} % ({'; '.join(m['hows'])}).")
    errs = ancf_errors(rows)
    for law in ("sliding", "unilateral", "free"):
        ks = sorted(k for k in errs if k[1] == law)
        if not ks:
            continue
        by_el = {}
        for k in ks:
            nref = len(ref_loads(rows, k[0], law))
            if len(errs[k]) != nref:
                continue
            w = max(errs[k].values(), key=abs)
            by_el.setdefault(k[2], []).append((abs(w), w, num(k[0])))
        if not by_el:
            continue
        parts = []
        for ne in sorted(by_el):
            a, w, psi = max(by_el[ne])
            parts.append(f"{ne} el. {100 * w:+.3f} % (ψ = {psi:g}°)")
        L.append(f"* ANCF {law}, worst error of the soleus elongation over all ψ and loads: " + ", ".join(parts) + ".")
        big = [ne for ne in sorted(by_el) if ne >= 4]
        if big:
            ok = all(max(by_el[ne])[0] <= target for ne in big)
            worst = [max(by_el[ne])[0] for ne in big]
            grows = all(b >= a for a, b in zip(worst, worst[1:]))
            L.append(f"  Target |error| ≤ {100 * target:.1f} % at {', '.join(str(n) for n in big)} elements at every ψ "
                     f"and load: **{'met' if ok else 'not met'}**"
                     + (f"; the worst error grows with the element count ({' → '.join(f'{100 * x:.3f} %' for x in worst)})."
                        if grows and len(worst) > 1 else
                        f"; worst |error| by element count: {' → '.join(f'{100 * x:.3f} %' for x in worst)}."))
    L.append("")
    return "\n".join(L)


def fmt_pct(x: float, digits: int = 3) -> str:
    return "—" if not np.isfinite(x) else f"{100 * x:+.{digits}f} %"


def render_md(rows: list, meta: dict) -> str:
    """The Markdown report, from the rows alone (so that --report can redo it from the CSV)."""
    import platform
    solids = [r for r in rows if r["model"] == SOLID and r["load_N"] not in ("", None)]
    refs = [r for r in rows if r["model"] == REF]
    checks = [r for r in rows if r["model"] == "check"]
    psis = sorted({num(r["psi_deg"]) for r in solids})
    laws = [l for l in ("sliding", "unilateral", "free") if any(r["law"] == l for r in solids)]
    hs = sorted({num(r["h_m"]) for r in solids}, reverse=True)
    L = []
    L.append("# Three-subtendon Achilles tendon: 3D solid reference with frictionless contact\n")
    gen = ("Generated by `scripts/verify_solid_contact.py` (`make verify-solid-contact`) from "
           "`docs/solid_contact.csv`; `--report` redraws this page and the figure from the CSV")
    if meta.get("argv") is not None:
        gen += f" (last invocation: `{meta['argv']}`"
        gen += f", {meta['total'] / 60:.0f} min, 1 core, {platform.machine()})" if meta.get("total") else ")"
    gen += "."
    src = sorted({r["note"] for r in rows if r["model"] == ANCF and str(r.get("note", "")).startswith("ancf_petsc")})
    if src:
        gen += "  ANCF: " + "; ".join(src) + "."
    L.append(gen + "\n")
    loads_text = ", ".join(f"{F:g}" for F in sorted({num(r["load_N"]) for r in solids}))
    L.append(summary_md(rows))
    L.append("""## What is solved

* **Geometry.** The Type III tendon of `configs/achilles_type3_psi*.yaml`: the outlines `soleus`,
  `medial_gastrocnemius`, `lateral_gastrocnemius` of `configs/data/achilles_type3_sections.yaml`
  (cubic splines, as the ANCF sections), L = 70 mm, pretwist ψ about the triple point
  (y, z) = (5.896, −2.984) mm.  Each subtendon is its own body: its straight prism is meshed on
  its own (no shared nodes; each body has its own interface faces), every geometry node is then
  mapped through `ancf_petsc.physics.geometry.place` (the ANCF pretwist map).  Quadratic
  tetrahedra (P2 geometry and displacement), quadrature degree 2 (as `verify_solid.py`).
* **Mesh.** Layered: each section is triangulated with size h (the shared interface curves get
  the same 1D mesh on both sides) and extruded in layers of h within 7 mm of each end and
  ≈ 2.5 h in between, each prism split into three tetrahedra.  Every size scales with h.  The
  layers keep a body's cross-section tessellation the same at every x, so a body sliding along
  x meets the same polygonal neighbour everywhere.  (With gmsh's unstructured tetrahedra the two
  P2 tessellations of a curved interface differ from point to point, and a body sliding over
  several elements rides over that washboard; the layers avoid it.)
* **Material.** Ψ = μ/2 (J^(−2/3) I1 − 3) + K/2 (J − 1)², μ = 103.1 / 143.2 / 226.7 MPa (soleus /
  medial / lateral), K = 0.86 GPa.
* **Supports and load.** Root faces x = 0 of all three bodies clamped (u = 0).  Soleus end face
  x = L: uniform dead traction F/A along +x (A = that face's area in the mesh), F = LOADS_TEXT N
  (the ANCF columns run all 13 of Table 1's levels; they are compared at these).  Gastrocnemius
  end faces free.
* **Contact.** Interfaces (slave on master): medial on soleus, lateral on soleus, medial on
  lateral (the soleus moves past its neighbours' ends, so they stay on it).  Gauss points on the
  slave's P2 faces (4 sub-triangles × 3 points) are projected onto the master's deformed P2 faces
  every Newton iteration (closest point, candidates from a k-d tree of the current face centres,
  the last face first); g = (x_s − x_m)·n_m along the outward master normal, minus the point's
  reference gap g0.  Points past the master's edge (its end, the edges of the interface strip)
  use the smooth extension of the nearest master face.  Constraints: one weighted gap per slave
  node, ḡ_k = Σ w φ_k (g − g0) / Σ w φ_k, with φ_k the node's hat function on the 4-triangle split
  of the P2 slave faces (mortar-type, piecewise-linear multipliers on quadratic faces; nodes on
  the clamped root carry none).  **sliding**: ḡ = 0 (holds in tension and compression);
  **unilateral**: ḡ ≥ 0, Λ ≥ 0, Λ ḡ = 0.  Enforced exactly by Lagrange multipliers: Newton on the
  symmetric saddle-point system with the consistent gap Hessian, MUMPS LDLᵀ, a new projection and
  factorisation every iteration.  The closest master face is chosen without memory of the
  previous iteration (the closest of the k nearest faces for feet near a face edge).
  **unilateral**: augmented-Lagrangian (Uzawa) iterations with ε = κ μ/h until the active set
  settles, then that set is solved again with exact multipliers and accepted only if its
  pressures are ≥ 0 and no free constraint penetrates: the answer does not depend on ε.
  There is no penalty in the answers: the checks below change the multipliers' unit k_s (and κ).
* **Kink floor.** Where the deformed P2 master surface has a kink between two faces, the closest
  face of a slave point can switch during a Newton solve; the contact force then jumps by (point
  force) × (kink angle) and Newton can cycle between the two sides.  Such a solve is accepted
  when five iterations no longer halve the residual and |R| < 10⁻⁴ of the applied force (counted
  in the run table below).
* **Quantities.** u_x at the reference end-section centroid place(L, c) of each body (the
  soleus' is the soleus elongation), and the mean u_x of the soleus end face.  The converged
  solid answer per (ψ, law, load) is `verify_solid.richardson` over the meshes (h ∝ DOFs^(−1/3),
  fitted order) or, when the changes do not shrink, the finest mesh with its last change as the
  uncertainty.
""".replace("LOADS_TEXT", loads_text or "—"))
    # runs
    if solids:
        L.append("## Solid runs\n")
        L.append("One core, serial; wall time of the load path (meshing excluded).  Kink floor: Newton solves "
                 "accepted at the kink floor (see above).\n")
        L.append("| ψ | law | h [mm] | DOFs | multipliers | Newton its | wall [s] | kink floor | stopped |")
        L.append("|---:|---|---:|---:|---:|---:|---:|---:|---|")
        for law in laws:
            for psi in psis:
                for h in hs:
                    fam = [r for r in solids if r["law"] == law and num(r["psi_deg"]) == psi and num(r["h_m"]) == h]
                    if not fam:
                        continue
                    stop = [r["note"] for r in rows if r["model"] == SOLID and r["law"] == law
                            and num(r["psi_deg"]) == psi and num(r["h_m"]) == h and r["load_N"] in ("", None)]
                    L.append(f"| {psi:g}° | {law} | {1e3 * h:.2f} | {fam[0]['dofs']} | {fam[0].get('multipliers', '')} | "
                             f"{sum(int(num(r['newton_its'])) for r in fam)} | {max(num(r['wall_s']) for r in fam):.0f} | "
                             f"{fam[0].get('kink_floor', '')} | {stop[0] if stop else ''} |")
        L.append("")
    # checks
    if checks:
        L.append("## Checks of the contact implementation\n")
        L.append("| check | number | details |\n|---|---:|---|")
        for c in checks:
            L.append(f"| {c['resolution']} | {num(c['uncertainty_rel']):.1e} | {c['note'].replace('|', '∣')} |")
        L.append("")
    # convergence tables
    if solids:
        L.append("## Mesh convergence of the solid (soleus elongation u_x [mm])\n")
        for law in laws:
            L.append(f"**{law}**" + (" (the soleus alone: no neighbours, same supports and load)" if law == "free" else "") + "\n")
            head = "| ψ | load [N] | " + " | ".join(f"h {1e3 * h:.2f} mm" for h in hs) + \
                " | reference | uncertainty | how |"
            L.append(head)
            L.append("|---:|---:|" + "---:|" * len(hs) + "---:|---:|---|")
            for psi in psis:
                for F in (10.0, 100.0, 400.0):
                    vals = []
                    for h in hs:
                        r = [x for x in solids if x["law"] == law and num(x["psi_deg"]) == psi
                             and num(x["h_m"]) == h and num(x["load_N"]) == F]
                        vals.append(f"{1e3 * num(r[0]['soleus_ux_m']):.5f}" if r else "—")
                    ref = [x for x in refs if x["law"] == law and num(x["psi_deg"]) == psi and num(x["load_N"]) == F]
                    if ref:
                        rr = ref[0]
                        L.append(f"| {psi:g}° | {F:g} | " + " | ".join(vals) +
                                 f" | {1e3 * num(rr['soleus_ux_m']):.5f} | {100 * num(rr['uncertainty_rel']):.3f} % | {rr['note']} |")
                    else:
                        L.append(f"| {psi:g}° | {F:g} | " + " | ".join(vals) + " | — | — | |")
            L.append("")
        # reference summary incl. neighbours
        L.append("## Solid reference: end-centroid u_x [mm]\n")
        L.append("| ψ | law | load [N] | soleus | ± | medial | lateral | soleus end face (mean) |")
        L.append("|---:|---|---:|---:|---:|---:|---:|---:|")
        for psi in psis:
            for law in laws:
                for F in (10.0, 100.0, 400.0):
                    ref = [x for x in refs if x["law"] == law and num(x["psi_deg"]) == psi and num(x["load_N"]) == F]
                    if not ref:
                        continue
                    r = ref[0]
                    f = lambda k: "—" if not np.isfinite(num(r[k])) else f"{1e3 * num(r[k]):.5f}"
                    L.append(f"| {psi:g}° | {law} | {F:g} | {f('soleus_ux_m')} | {100 * num(r['uncertainty_rel']):.3f} % | "
                             f"{f('medial_ux_m')} | {f('lateral_ux_m')} | {f('soleus_face_ux_m')} |")
        L.append("")
        # contact diagnostics at 400 N on the finest mesh
        diag = [r for r in solids if r["law"] != "free" and num(r["load_N"]) == 400.0 and num(r["h_m"]) == hs[-1]]
        if diag:
            L.append("Contact state at 400 N on the finest mesh (pressure p = Λ_k / ∫φ_k, positive = compression; "
                     "pointwise |g − g0| is what the weighted constraints leave between the quadrature points):\n")
            L.append("| ψ | law | pointwise max |g − g0| [µm] | contact state |\n|---:|---|---:|---|")
            for r in diag:
                L.append(f"| {num(r['psi_deg']):g}° | {r['law']} | {1e6 * num(r['gap_max_m']):.3f} | {r['note']} |")
            L.append("")
    # ANCF comparison
    errs = ancf_errors(rows)
    if errs:
        L.append("## ANCF against the solid reference\n")
        L.append("Relative error (u_ANCF − u_ref)/u_ref of the soleus elongation, ANCF 3363 with 2 axial "
                 "Gauss points, `fix: clamped`, `traction_force` at the soleus' last node, "
                 "`contact: {mode: sliding | unilateral}` (free: the soleus beam alone).  Worst = largest "
                 "|error| over the solid's load levels (signed value shown).\n")
        L.append("| ψ | law | elements | worst over 10–400 N | at 10 N | at 100 N | at 400 N | reference uncertainty (max over loads) |")
        L.append("|---:|---|---:|---:|---:|---:|---:|---:|")
        fails = {(r["psi_deg"], r["law"], r["elements"]): r["note"] for r in rows
                 if r["model"] == ANCF and str(r.get("note", "")).startswith("FAILED")}
        for psi in psis:
            for law in ("sliding", "unilateral", "free"):
                ks = sorted(k for k in errs if num(k[0]) == psi and k[1] == law)
                unc = [num(x["uncertainty_rel"]) for x in refs if num(x["psi_deg"]) == psi and x["law"] == law]
                for k in ks:
                    e = errs[k]
                    nref = len(ref_loads(rows, psi, law))
                    worst = max(e.values(), key=abs) if len(e) == nref else float("nan")
                    note = "" if len(e) == nref else f" (only {len(e)} of {nref} levels)"
                    L.append(f"| {psi:g}° | {law} | {k[2]} | {fmt_pct(worst)}{note} | {fmt_pct(e.get(10.0, np.nan))} | "
                             f"{fmt_pct(e.get(100.0, np.nan))} | {fmt_pct(e.get(400.0, np.nan))} | "
                             f"{100 * max(unc):.3f} % |")
                for (p, l, ne), note in sorted(fails.items()):
                    if num(p) == psi and l == law and not any(k[2] == int(num(ne)) for k in ks):
                        L.append(f"| {psi:g}° | {law} | {ne} | {note} | | | | |")
        L.append("")
        L.append("![ANCF error vs elements](figures/solid_contact.png)\n")
        L.append(limits_md(rows, errs))
    notes = os.path.join(ROOT, "docs", "solid_contact.notes")
    if os.path.exists(notes):
        with open(notes, encoding="utf-8") as fh:
            L.append(fh.read().rstrip() + "\n")
    return "\n".join(L) + "\n"
