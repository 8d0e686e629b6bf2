"""Three-subtendon Achilles tendon as a 3D solid with frictionless contact: a reference for ANCF.

The Type III tendon (soleus, medial and lateral gastrocnemius; configs/achilles_type3_psi*.yaml)
is solved twice, serially on one core:

* **solid**: three separate bodies of quadratic tetrahedra (gmsh 4.8, dolfinx 0.5.2).  Each
  subtendon's straight prism is its own gmsh volume (not fragmented: the interface nodes are
  duplicated and each body has its own interface faces); every geometry node is then mapped
  through the ANCF pretwist map ``place`` (as in scripts/verify_solid.py).  Same neo-Hookean
  energy as the beams, Ψ = μ/2 (J^(-2/3) I1 − 3) + K/2 (J − 1)², one μ per body.  Root faces
  x = 0 clamped; the soleus end face x = L carries the uniform dead traction F/A; the
  gastrocnemius end faces are free.
* **ANCF**: the same three beams in-process (``parse_config`` + ``run_model``), ``fix: clamped``,
  ``traction_force`` at the soleus' last node, 2 axial Gauss points, ``contact: {mode: ...}``.

Contact (solid).  On each interface one side is the slave (medial on soleus, lateral on soleus,
medial on lateral): Gauss points on its P2 faces are projected (closest point, every Newton
iteration, candidates from a cKDTree of the current master face centroids) onto the other body's
deformed P2 faces; g = (x_s − x_m)·n_m along the outward master normal, minus the reference gap
g0 of the point (the two tessellations of the curved interface are not the same surface).  The
constraints are mortar-type weighted gaps, one per slave node,

    ḡ_k = Σ_q w_q φ_k(q) (g_q − g0_q) / Σ_q w_q φ_k(q),

with φ_k the hat function of slave node k on the 4-triangle split of each P2 slave face
(piecewise-linear multipliers on quadratic faces: non-negative, partition of unity; as many
constraints as slave nodes, so the non-matching interface is not over-constrained).  They are
enforced exactly by Lagrange multipliers (Λ_k = k_s z_k, force): Newton on the symmetric
saddle-point system [[K + K_geo, −k_s Gᵀ], [−k_s G, 0]] with the consistent gap Hessian in K_geo,
factored by MUMPS LDLᵀ.  ``sliding``: ḡ = 0 (tension and compression).  ``unilateral``: ḡ ≥ 0,
Λ ≥ 0, Λ ḡ = 0: augmented-Lagrangian (Uzawa) iterations λ ← max(0, λ − ε ḡ) around a Newton
solve of the regularised problem (ε = κ μ/h), then the active set is "polished" with exact
multipliers (the sliding solver on the active constraints) and accepted when its pressures are
≥ 0 and the free constraints do not penetrate; the answer must not depend on κ or k_s (checked).

Projection.  The closest master face of a slave point is history-free: feet within 2 % of a face
edge (in the face's parameters) are searched among the k nearest faces and the closest kept, and
points past a face border take the face whose unclipped foot is least outside.  Where the
deformed master surface has a kink, the closest face of a point can still switch inside a
Newton solve, which makes the contact force jump by (point force) x (kink angle); Newton then
may cycle between the two sides.  Such a state is accepted ("kink floor", counted and reported)
when five iterations no longer halve the residual and it is below 1e-4 of the applied force.

Usage (make verify-solid-contact runs the first two; about 75 min on one shared core):
  python scripts/verify_solid_contact.py                       # sliding study + free soleus + checks
  python scripts/verify_solid_contact.py --merge --no-selftest --no-free --no-checks --laws unilateral       --psi 45 --h 2e-3,1.4e-3 --loads 10,20,40 --max-increment 10   # unilateral rows, added to the CSV
  python scripts/verify_solid_contact.py --ancf-src DIR        # ANCF (and configs) from an export of a commit
  python scripts/verify_solid_contact.py --quick               # smoke run, coarse meshes (into results/)
  python scripts/verify_solid_contact.py --selftest            # contact implementation checks
  python scripts/verify_solid_contact.py --replot              # figure + report from the CSV
Writes docs/solid_contact.csv, docs/solid_contact.md, docs/figures/solid_contact.png.
"""
from __future__ import annotations

import os
import sys
import tempfile
import time

from ancf_verify.cli import Parser, counts, numbers, out_dir, sizes
from ancf_verify.contact.beams import run_ancf
from ancf_verify.contact.report import plot, render_md
from ancf_verify.contact.rows import (REF, ancf_rows, independence_rows, read_csv, reference_rows, row_key,
    selftest_rows, solid_rows, write_csv)
from ancf_verify.contact.selftest import selftest
from ancf_verify.contact.solid import run_solid
from ancf_verify.contact.tendon import ContactError, tendon_sections, use_source
from ancf_verify.roots import ROOTS
from ancf_verify.stack import import_stack


def main(argv=None) -> int:
    ap = Parser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--psi", type=numbers, default="0,15,45", help="pretwist angles [deg]")
    ap.add_argument("--laws", default="sliding", help="contact laws: sliding,unilateral")
    ap.add_argument("--h", type=sizes, default="2e-3,1.4e-3,1.15e-3", help="solid mesh sizes [m], coarse to fine")
    ap.add_argument("--elements", type=counts, default="2,4,8,16", help="ANCF elements per subtendon")
    ap.add_argument("--quick", action="store_true", help="coarse meshes only (smoke run)")
    ap.add_argument("--selftest", action="store_true", help="only the contact self-tests")
    ap.add_argument("--no-selftest", action="store_true", help="skip the self-tests in a full run")
    ap.add_argument("--patch-tests", action="store_true", help="also the two-block patch tests (slow)")
    ap.add_argument("--no-checks", action="store_true", help="skip the k_s / kappa checks")
    ap.add_argument("--no-free", action="store_true", help="skip the free soleus")
    ap.add_argument("--rule-points", type=int, default=3, choices=(3, 6, 7),
                    help="Gauss points per sub-triangle of a slave face (4 sub-triangles)")
    ap.add_argument("--replot", action="store_true", help="figure and report from the CSV (no solving)")
    ap.add_argument("--report", action="store_true", help="same as --replot")
    ap.add_argument("--out", help="output directory (default docs/; with --quick results/verify_solid_contact_quick/)")
    ap.add_argument("--loads", type=numbers, default="10,20,40,100,200,300,400",
                    help="solid load levels [N] (the ANCF columns run all of Table 1's levels)")
    ap.add_argument("--max-increment", type=float, default=100.0, help="largest solid load increment [N]")
    ap.add_argument("--free-psi", type=numbers, default="0,15,45", help="pretwists at which the free soleus is solved too")
    ap.add_argument("--ancf-src", default="",
                    help="import ancf_petsc (and read configs/) from this directory, e.g. an export of a commit")
    ap.add_argument("--ancf-label", default="the working tree", help="what --ancf-src is (recorded in the CSV)")
    ap.add_argument("--no-solid", action="store_true", help="only the ANCF columns (with --merge)")
    ap.add_argument("--root", default="clamped", choices=ROOTS,
                    help="the roots of solid and beams: clamped (u = 0; fix: clamped) or plane (u_x = 0, "
                         "free in the plane; fix: plane); with plane write to another --out")
    ap.add_argument("--penalty", type=float, default=0.0,
                    help="solve the solid's laws with a pure penalty eps = PENALTY mu/h instead of exact "
                         "multipliers (a sensitivity study: rows of model 'solid P2 tet, penalty', no reference)")
    ap.add_argument("--merge", action="store_true",
                    help="keep the rows of the existing CSV that this run does not redo")
    args = ap.parse_args(argv)
    laws = [law.strip() for law in args.laws.split(",") if law.strip()]
    if not laws or set(laws) - {"sliding", "unilateral"}:
        ap.error(f"--laws: expected sliding and/or unilateral separated by commas; got {args.laws!r}")
    args.out = out_dir(args.out, args.quick, "verify_solid_contact")
    try:
        use_source(args.ancf_src, args.ancf_label)
    except ContactError as exc:
        ap.error(str(exc))
    csv_path = os.path.join(args.out, "solid_contact.csv")
    md_path = os.path.join(args.out, "solid_contact.md")
    png_path = os.path.join(args.out, "figures", "solid_contact.png")
    os.makedirs(os.path.dirname(png_path), exist_ok=True)
    if args.replot or args.report:
        rows = [r for r in read_csv(csv_path) if r["model"] != REF]
        rows += reference_rows(rows)
        write_csv(csv_path, rows)
        rows = read_csv(csv_path)
        plot(png_path, rows)
        with open(md_path, "w") as fh:
            fh.write(render_md(rows, {}))
        print(f"[solid-contact] rewrote {md_path} and {png_path} from {csv_path}")
        return 0
    import_stack()
    t_start = time.perf_counter()
    secs = tendon_sections()
    old_rows = [r for r in read_csv(csv_path) if r["model"] != REF] \
        if args.merge and os.path.exists(csv_path) else []

    def finish(rows, meta):
        keys = {row_key(r) for r in rows}
        rows = [r for r in old_rows if row_key(r) not in keys] + rows
        rows = [r for r in rows if r["model"] != REF]
        rows += reference_rows(rows)
        write_csv(csv_path, rows)
        rows = read_csv(csv_path)          # the page is what the CSV says (as --report makes it)
        plot(png_path, rows)
        meta["total"] = time.perf_counter() - t_start
        with open(md_path, "w") as fh:
            fh.write(render_md(rows, meta))
        print(f"[solid-contact] {meta['total']:.0f} s; wrote {md_path}, {csv_path}, {png_path}")

    if args.selftest:
        st = selftest(secs, patch=args.patch_tests)
        rows = selftest_rows(st)
        for r in rows:
            print(f"[selftest] {r['resolution']}: {r['uncertainty_rel']:.2e}")
        if args.merge:
            finish(rows, {"argv": " ".join(sys.argv[1:])})
        return 0
    psis = args.psi
    hs = args.h
    elements = args.elements
    loads = args.loads
    free_psis = args.free_psi
    if args.quick:
        hs, elements = [3e-3, 2e-3], [e for e in elements if e <= 4] or [2]
    kw = {"rule_points": args.rule_points, "root": args.root, "penalty": args.penalty}
    rows: list = []
    meta = {"argv": " ".join(sys.argv[1:]), "h": hs, "rule_points": args.rule_points}
    runs_done = {}

    def save():
        keys = {row_key(r) for r in rows}
        keep = [r for r in old_rows if row_key(r) not in keys]
        write_csv(csv_path, keep + rows + reference_rows(keep + rows))

    if not args.no_selftest:
        print("[solid-contact] self-tests", flush=True)
        rows += selftest_rows(selftest(secs, patch=args.patch_tests))
        save()
    with tempfile.TemporaryDirectory(prefix="solid_contact_") as tmp:
        for psi in psis:
            free = not args.no_free and psi in free_psis
            runs = [(None, (0,))] if free else []
            runs += [(law, (0, 1, 2)) for law in laws]
            for law, bodies in (runs if not args.no_solid else []):
                for h in hs:
                    print(f"[solid] psi {psi:g}, {law or 'free soleus'}, h {h * 1e3:.2f} mm", flush=True)
                    r = run_solid(secs, psi, law, h, loads=loads, bodies=bodies,
                                  max_increment=args.max_increment, **kw)
                    runs_done[(psi, law, h)] = r
                    st = r["stats"]
                    print(f"[solid]   {r['dofs']} DOFs, {r['nc']} multipliers, {r['wall']:.0f} s "
                          f"(+ mesh {r['t_mesh']:.0f} s), {st['newton']} Newton its, "
                          f"kink-floor acceptances {st.get('stalls', 0)} (|R|/F up to {st.get('stall_max', 0):.1e})"
                          + ("" if r["ok"] else f", FAILED: {r['msg']}"), flush=True)
                    rows += solid_rows(r)
                    save()
            for law in ([None] if free else []) + laws:
                for ne in elements:
                    a = run_ancf(psi, law, ne, tmp, args.root)
                    print(f"[ancf] psi {psi:g}, {law or 'free'}, {ne} el.: "
                          + (f"soleus u_x(400 N) {1e3 * a['levels'][-1]['u']['soleus'][0]:.5f} mm, "
                             f"{a['wall']:.1f} s" if a["ok"] else f"FAILED ({a['msg']})"), flush=True)
                    rows += ancf_rows(a)
            save()
        if not args.no_checks and not args.no_solid:
            psi, h = psis[-1], hs[0]
            print(f"[solid-contact] independence checks at psi {psi:g}, h {h * 1e3:.2f} mm", flush=True)
            for law in laws:
                opt = dict(kw, loads=loads, max_increment=args.max_increment)
                base = runs_done.get((psi, law, h)) or run_solid(secs, psi, law, h, log=None, **opt)
                other = run_solid(secs, psi, law, h, log=None, ks=100.0 * base["ks"], **opt)
                rows += independence_rows(base, other, f"{law}: multiplier unit k_s x 100")
                if law == "unilateral":
                    other = run_solid(secs, psi, law, h, log=None, kappa=10.0, **opt)
                    rows += independence_rows(base, other, f"{law}: penalty eps = kappa mu/h, kappa 1 -> 10")
                save()
    finish(rows, meta)
    return 0
