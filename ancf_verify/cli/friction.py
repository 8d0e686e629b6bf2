"""Three-subtendon Achilles tendon with Coulomb friction: 3D solid reference against ANCF (issue 27).

The solid of scripts/verify_solid_contact.py (dolfinx P2 tetrahedra, three bodies, mortar-type
weighted gaps held at zero by exact multipliers: the ``sliding`` normal law) with the beam
model's Coulomb law at the slave Gauss points (ancf_verify/friction/model.py: reference partners,
incremental return mapping from the last accepted increment, bound μ max(p, 0) with p the solid's
contact pressure, stick regularised by k = ``stick`` μ_max/h).  Clamped roots, uniform dead
traction on the soleus end face, Table 1's load levels 10 … 400 N, every increment accepted into
the friction history (as ancf-solve does).

ANCF: the same tendon in-process (``verify_solid_contact.tendon_config``: ``fix: clamped``,
``traction_force`` at the soleus' last node, 2 axial points) with ``contact: {mode: sliding,
tangential: {law: coulomb, friction: μ}}`` at 4/8/16 elements (tangential multipliers, exact
stick: no stick stiffness), at the default augmentation c and at c x 10 and c / 10 (c only steers
the semi-smooth Newton iteration: the answer must not depend on it, and that is measured), in the
default pressure space or in richer ones (``--ancf-spaces``, solid_friction_report.SPACES).

Usage (``make verify-solid-friction``; about 2 h on one shared core):
  python scripts/verify_solid_friction.py                    # FD check, solid study, checks, ANCF
  python scripts/verify_solid_friction.py --selftest         # the friction tangent against FD
  python scripts/verify_solid_friction.py --no-solid --merge # ANCF columns only (CSV kept)
  python scripts/verify_solid_friction.py --replot           # figure and page section from the CSV
  python scripts/verify_solid_friction.py --no-solid --merge --no-selftest --ancf-spaces "quadratic across"
                                                             # the beams with a richer pressure space
  python scripts/verify_solid_friction.py --free-zone 0.01 --no-selftest --ancf-augmentations default
                                                             # diagnostic: no friction within 10 mm of the clamp
Writes docs/solid_friction.csv, docs/figures/solid_friction.png and the section "Against a 3D
solid with friction" of docs/interface.md (between its markers; the rest of the page is kept).
"""
from __future__ import annotations

import os
import sys
import tempfile
import time

from ancf_verify.cli import Parser, counts, numbers, sizes
from ancf_verify.contact.mesh import LocalSize
from ancf_verify.contact.tendon import LOADS, tendon_sections
from ancf_verify.friction.beams import run_ancf, zone_label
from ancf_verify.friction.page import finish
from ancf_verify.friction.rows import (Paths, SPACES, ancf_rows, fd_rows, read_csv, row_key, solid_rows,
    write_csv)
from ancf_verify.friction.study import profiles, run_solid, selftest_fd, spaces
from ancf_verify.paths import ROOT
from ancf_verify.stack import import_stack


# ============================================================================================
# Driver
# ============================================================================================
def main(argv=None) -> int:
    ap = Parser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--psi", type=numbers, default="45,0", help="pretwist angles [deg]")
    ap.add_argument("--mu", type=float, default=0.3, help="friction coefficient")
    ap.add_argument("--h", type=sizes, default="2e-3,1.4e-3,1.15e-3", help="solid mesh sizes [m] at the first pretwist, coarse to fine")
    ap.add_argument("--h-more", type=sizes, default="2e-3,1.4e-3", help="solid mesh sizes at the other pretwists")
    ap.add_argument("--h-interface", default="",
                    help="local refinement: element size [m] around the --refine-at interface, one per --h (then "
                         "the bulk size; the axial layers follow it; '' or 0: uniform), e.g. --h 2e-3,2e-3 "
                         "--h-interface 1e-3,7e-4")
    ap.add_argument("--refine-at", default="mg_sol", help="the interface curve of --h-interface")
    ap.add_argument("--loads", type=numbers, default="", help="solid load levels [N] (default: Table 1's 10 ... 400 N)")
    ap.add_argument("--stick", type=float, default=100.0, help="solid stick stiffness k in mu_max/h")
    ap.add_argument("--elements", type=counts, default="4,8,16", help="ANCF elements per subtendon")
    ap.add_argument("--ancf-augmentations", default="default,10,0.1",
                    help="ANCF augmentation factors c of contact.tangential ('default': the law's, "
                         "G/E of the softer beam since 2026-12-02, 1 before)")
    ap.add_argument("--ancf-spaces", default="default",
                    help="ANCF pressure spaces separated by ';': 'default' (linear along × linear across) and/or "
                         + ", ".join(f"'{n}'" for n in SPACES))
    ap.add_argument("--element", default="",
                    help="every beam's element of the ANCF columns, e.g. 33103 ('': the config's default, 3363); "
                         "the rows' model then names it ('ANCF 33103 2pt') and the generated page tables skip them")
    ap.add_argument("--max-increment", type=float, default=50.0, help="largest solid load increment [N]")
    ap.add_argument("--free-zone", type=float, default=0.0,
                    help="a diagnostic [m]: the runs without friction below x = this (solid: coarsest mesh only)")
    ap.add_argument("--selftest", action="store_true", help="only the FD check of the friction tangent")
    ap.add_argument("--no-selftest", action="store_true")
    ap.add_argument("--no-checks", action="store_true", help="skip the regularisation/slip/increment checks")
    ap.add_argument("--no-solid", action="store_true", help="only the ANCF columns")
    ap.add_argument("--no-ancf", action="store_true", help="only the solid")
    ap.add_argument("--merge", action="store_true", help="keep the CSV rows this run does not redo")
    ap.add_argument("--profiles", type=numbers, default="100", help="load levels [N] of the pressure/friction profiles "
                    "(solid h = the coarsest mesh, mu = 0 and mu; ANCF at each element count; '' for none)")
    ap.add_argument("--replot", action="store_true", help="figure and page section from the CSV")
    ap.add_argument("--out", default=os.path.join(ROOT, "docs"))
    args = ap.parse_args(argv)
    unknown = [n for n in spaces(args) if n is not None and n not in SPACES]
    if unknown:
        print(f"verify_solid_friction: --ancf-spaces: unknown {unknown}; known: default, {', '.join(SPACES)}",
              file=sys.stderr)
        return 2
    try:
        locs = local_sizes(args, len(args.h))
    except ValueError as exc:
        ap.error(str(exc))
    paths = Paths(args.out)
    if args.replot:
        finish(paths, read_csv(paths.csv), {})
        return 0
    import_stack()
    os.makedirs(args.out, exist_ok=True)   # the CSV is saved after each run (a new --out failed there)
    t_start = time.perf_counter()
    secs = tendon_sections()
    rows = read_csv(paths.csv) if args.merge and os.path.exists(paths.csv) else []

    def save(new):
        nonlocal rows
        keys = {row_key(r) for r in new}
        rows = [r for r in rows if row_key(r) not in keys] + new
        write_csv(paths.csv, rows)

    if not args.no_selftest:
        print("[solid-friction] friction tangent against finite differences", flush=True)
        save(fd_rows(selftest_fd(secs)))
        if args.selftest:
            finish(paths, rows, {"argv": " ".join(sys.argv[1:])})
            return 0
    psis = args.psi
    hs = args.h
    loads = args.loads or list(LOADS)
    mu = args.mu
    zone = args.free_zone
    for psi in psis:
        more = args.h_more
        for h, loc in list(zip(hs, locs) if psi == psis[0] else zip(more, [None] * len(more)))[:1 if zone else None]:
            if args.no_solid:
                break
            print(f"[solid] psi {psi:g}, mu {mu:g}, h {h * 1e3:.2f} mm" + (f", {loc.label()}" if loc else "")
                  + f", stick {args.stick:g}" + (f", no friction below x = {zone * 1e3:g} mm" if zone else ""),
                  flush=True)
            r = run_solid(secs, psi, h, mu, args.stick, max_increment=args.max_increment, free_zone=zone,
                          loads=loads, local=loc)
            save(solid_rows(r, psi, mu, zone_label(f"stick {args.stick:g}", zone)))
        if not args.no_checks and not args.no_solid and not zone and psi == psis[0]:
            h = hs[0]
            for label, kw in ((f"stick {10 * args.stick:g}", {"stick": 10 * args.stick}),
                              ("slip closest", {"slip": "closest"}),
                              ("increments 10 N", {"max_increment": 10.0})):
                print(f"[solid] check {label}: psi {psi:g}, h {h * 1e3:.2f} mm", flush=True)
                opt = {"stick": args.stick, "max_increment": args.max_increment} | kw
                save(solid_rows(run_solid(secs, psi, h, mu, **opt), psi, mu, label))
        if args.no_ancf:
            continue
        with tempfile.TemporaryDirectory(prefix="solid_friction_") as tmp:
            for space, aug in ((s, a) for s in spaces(args) for a in args.ancf_augmentations.split(",")):
                c = None if aug == "default" else float(aug)
                for ne in args.elements:
                    a = run_ancf(psi, ne, mu, c, tmp, zone, space, element=args.element or None)
                    last = a["levels"][-1] if a["levels"] else None
                    print(f"[ancf] psi {psi:g}, {ne} el., element {args.element or 'default'}, augmentation {aug}, "
                          f"pressure {space or 'default'}: "
                          + (f"{last['load']:g} N, soleus u_x {1e3 * last['u']['soleus']:.5f} mm" if last else "")
                          + (f", {a['wall']:.0f} s" if a["ok"] else f" FAILED ({a['msg']})"), flush=True)
                    save(ancf_rows(a, mu))
    levels = args.profiles if not zone else []
    if levels:
        profiles(secs, args, levels, psis[0])
    finish(paths, rows, {"argv": " ".join(sys.argv[1:]), "total": time.perf_counter() - t_start})
    return 0


def local_sizes(args, n: int) -> list:
    """One contact.mesh.LocalSize (or None: uniform) per --h from --h-interface and --refine-at."""
    try:
        hi = [float(x) for x in args.h_interface.split(",") if x.strip()]
    except ValueError:
        raise ValueError(f"--h-interface: expected sizes [m] separated by commas, e.g. 1e-3,7e-4; "
                         f"got {args.h_interface!r}") from None
    if hi and len(hi) != n or any(not x >= 0 for x in hi):
        raise ValueError(f"--h-interface: one size >= 0 per --h ({n}; 0: uniform); got {args.h_interface!r}")
    return [LocalSize(args.refine_at, x) if x > 0 else None for x in hi] or [None] * n
