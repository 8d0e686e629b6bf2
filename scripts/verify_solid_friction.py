#!/usr/bin/env python3
"""Three-subtendon Achilles tendon with Coulomb friction: 3D solid reference against ANCF (issue 27).

The solid of scripts/verify_solid_contact.py (dolfinx P2 tetrahedra, three bodies, mortar-type
weighted gaps held at zero by exact multipliers: the ``sliding`` normal law) with the beam
model's Coulomb law at the slave Gauss points (scripts/solid_friction.py: reference partners,
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

import argparse
import os
import sys
import tempfile
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")
HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402

import solid_friction as sf  # noqa: E402
import solid_friction_page as page  # noqa: E402
import solid_friction_report as rep  # noqa: E402
import verify_solid_contact as vsc  # noqa: E402

LOADS = vsc.LOADS                   # Table 1's levels [N]
IFACES = [n for n, _, _ in vsc.INTERFACES]
#: the beam model's config key of the Coulomb law's augmentation factor c (contact.tangential.<key>)
AUG_KEY = "augmentation"


def zone_label(variant: str, zone: float) -> str:
    """The variant of a free-zone diagnostic run (rep.ZONE marks it)."""
    return f"{variant}{rep.ZONE}{zone * 1e3:g} mm" if zone else variant


#: friction's held root functions as docs/solid_friction.csv was measured: kept (the default until
#: 2026-11-26; the default merge moves the beams' soleus by +0.19 / +0.08 / +0.02 % at 4 / 8 / 16
#: elements, docs/interface.md "Verdict and why")
SUPPORTED_ENDS = "keep"


def ancf_config(psi: float, elements: int, mu: float, aug: float | None, out: str, space: str | None = None) -> dict:
    """verify_solid_contact's frictionless comparison config with Coulomb friction added (and the
    contact keys of the pressure space ``space``, a rep.SPACES name; None: the default)."""
    raw = vsc.tendon_config(psi, elements, "sliding", out)
    raw["contact"]["tangential"] = {"law": "coulomb", "friction": mu, "supported_ends": SUPPORTED_ENDS}
    if aug is not None:
        raw["contact"]["tangential"][AUG_KEY] = aug
    if space:
        raw["contact"].update(rep.SPACES[space])
    return raw


def run_ancf(psi: float, elements: int, mu: float, aug: float | None, tmp: str, zone: float = 0.0,
             space: str | None = None) -> dict:
    """One ANCF column in-process: per level the probes' u_x, iterations and shear forces
    (``zone`` > 0, a diagnostic: no friction at contact points below x = zone [m]; ``space``:
    the pressure space, a rep.SPACES name, None the default)."""
    import contextlib

    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    from solid_friction_profiles import BeamFreeZone
    out = os.path.join(tmp, f"ancf_{psi:g}_{elements}_{aug}_{zone:g}_{space}".replace(" ", "_"))
    t0 = time.perf_counter()
    try:
        with BeamFreeZone(zone, elements) if zone else contextlib.nullcontext():
            res = run_model(parse_config(ancf_config(psi, elements, mu, aug, out, space), base_dir=vsc.CONFIGS),
                            log=lambda *_: None)
        status, message, s = res.status, str(res.message), res.summary
    except Exception as exc:   # record and go on
        status, message, s = "failed", f"{type(exc).__name__}: {exc}", None
    rec = {"psi": psi, "elements": elements, "augmentation": aug, "zone": zone, "space": space,
           "ok": status == "completed",
           "msg": "" if status == "completed" else message, "wall": time.perf_counter() - t0,
           "levels": [], "dofs": int(s["dofs"]) if s else 0,
           "k": None}
    for st in (s or {}).get("steps", []):
        forces = {}
        for key, c in st.get("contact", {}).items():
            name = key.split()[0]
            forces[name] = c.get("shear_force", [np.nan])[0]
            forces[name + "_pmax"] = c.get("max_pressure", np.nan)
            forces[name + "_stick"] = c.get("stick_share", np.nan)
        rec["levels"].append({"load": float(st["load_factor"]), "its": int(st["iterations"]),
                              "u": {vsc.SHORT[i]: st["probes"][n]["displacement"][0]
                                    for i, n in enumerate(vsc.NAMES)}, "friction": forces})
    return rec


def run_solid(secs, psi: float, h: float, mu: float, stick: float, slip: str = "partner",
              max_increment: float = 50.0, loads=LOADS, log=print, free_zone: float = 0.0) -> dict:
    """One solid run with friction (verify_solid_contact.run_solid with FrictionProblem;
    ``free_zone`` > 0, a diagnostic: no friction at slave points below x = free_zone [m])."""
    return vsc.run_solid(secs, psi, "sliding", h, loads=list(loads), max_increment=max_increment, log=log,
                         problem_class=sf.FrictionProblem, mu=mu, stick=stick, slip=slip, free_zone=free_zone)


# ============================================================================================
# The tangent against finite differences
# ============================================================================================
def selftest_fd(secs, h: float = 3e-3, psi: float = 45.0, log=print) -> list:
    """Central differences of the residual (friction included) against the assembled Jacobian on
    the tendon mesh, at a deformed state with 2 mm of sliding, pressures of 1-1.6 MPa and a
    history that leaves about half of the points sticking (each slip measure)."""
    out = []
    for slip in ("partner", "closest"):
        rng = np.random.default_rng(3)
        P, _ = vsc.tendon_problem(secs, psi, h, "sliding", problem_class=sf.FrictionProblem, mu=0.3, slip=slip)
        P.set_load(60.0)
        u = _sliding_state(P)
        z = P.ak_all * (1.0 + 0.6 * rng.random(P.nc)) * 1e6 / P.ks
        x = P.positions(u)
        c0 = vsc.Problem.residual(P, u, z, False)[2]
        for fr, ev in zip(P.fr, c0["evs"]):
            n = ev["n"]
            t = rng.normal(size=n.shape)
            t -= np.einsum("pi,pi->p", t, n)[:, None] * n
            t /= np.linalg.norm(t, axis=1)[:, None]
            r = np.where(rng.random(len(n)) < 0.5, 0.3, 3.0)       # sticks (0.3) or slips (3)
            fr.sigma0 = np.zeros_like(n)
            shift = t * (r * 0.3e6 / P.k_stick)[:, None]
            if slip == "partner":
                fr.d0 = fr.relative(x) - shift
            else:   # the last closest point, moved back along the surface
                fr.mf_n, fr.z_n = ev["mf"].copy(), ev["z"].copy()
                fr.z_n = fr.z_n - np.einsum("pai,pi->pa", ev["T"], shift) / np.einsum("pai,pai->pa", ev["T"], ev["T"])
        du = rng.normal(size=P.ndof) * P.mask
        dz = rng.normal(size=P.nc) * P.ak_all * 1e5 / P.ks
        R, Jm, c = P.residual(u, z, matrix=True)
        per = c["friction"]["per"]
        d = np.concatenate([du, dz])
        Jd, Jf = Jm @ d, c["friction"]["Kuu"] @ du + c["friction"]["Kuz"] @ dz
        rec = {"slip": slip, "h": h, "ndof": P.ndof, "nq": sum(len(q["p"]) for q in per),
               "stick": sum(int(q["stick"].sum()) for q in per), "slide": sum(int(q["slide"].sum()) for q in per)}
        for eps in (1e-5, 1e-6, 1e-7, 1e-8):
            e = eps * h
            Rp, _, cp = P.residual(u + e * du, z + e * dz)
            Rm, _, cm = P.residual(u - e * du, z - e * dz)
            same = all(np.array_equal(a["stick"], b["stick"]) and np.array_equal(a["slide"], b["slide"])
                       for cc in (cp, cm) for a, b in zip(cc["friction"]["per"], per))
            ff = (cp["friction"]["f"] - cm["friction"]["f"]) / (2 * e)
            rec[eps] = {"full": float(np.linalg.norm((Rp - Rm) / (2 * e) - Jd) / np.linalg.norm(Jd)),
                        "friction": float(np.linalg.norm(ff - Jf) / np.linalg.norm(ff)), "same": same}
            log(f"  [fd] {slip:8s} eps {eps:g} h: |FD - J d|/|J d| full {rec[eps]['full']:.2e}, friction forces "
                f"{rec[eps]['friction']:.2e}" + ("" if same else " (stick/slip set changed within +-eps)"))
        log(f"  [fd] {slip}: {rec['nq']} points, {rec['stick']} stick, {rec['slide']} slip")
        out.append(rec)
    return out


def _sliding_state(P) -> np.ndarray:
    """verify_solid_contact.selftest_fd's deformed state: stretch, 2 mm soleus slide, twist."""
    X = P.X
    dm = P.V.dofmap.list.array.reshape(-1, 10)
    sol = np.unique(dm[P.ct.indices[P.ct.values == 1]].ravel())
    U = np.zeros_like(X)
    U[:, 0] = 0.005 * X[:, 0]
    U[sol, 0] += 0.03 * X[sol, 0]
    U[:, 1] += 0.01 * (X[:, 0] / vsc.LENGTH) * (X[:, 2] - vsc.AXIS[1])
    U[:, 2] -= 0.01 * (X[:, 0] / vsc.LENGTH) * (X[:, 1] - vsc.AXIS[0])
    return U.ravel() * P.mask


def profiles(secs, args, levels: list, psi: float) -> None:
    """Pressure and friction along the tendon (solid_friction_profiles.py): the solid on the
    coarsest mesh, frictionless and with μ; the ANCF columns (default augmentation, then the
    others where it fails), frictionless and with μ; written to solid_friction_profiles.csv."""
    import solid_friction_profiles as pf
    path = os.path.join(args.out, "solid_friction_profiles.csv")
    rows = []
    h = [float(x) for x in args.h.split(",")][0]
    with tempfile.TemporaryDirectory(prefix="solid_friction_profiles_") as tmp:
        for F in levels:
            for mu in (0.0, args.mu):
                if not args.no_solid:
                    print(f"[profile] solid, mu {mu:g}, h {h * 1e3:.2f} mm, {F:g} N", flush=True)
                    rows += pf.solid_profile(secs, psi, h, mu, F, args.stick)
                for space, ne in ((s, e) for s in spaces(args) for e in [int(e) for e in args.elements.split(",")]):
                    for aug in (args.ancf_augmentations.split(",") if mu else ["default"]):
                        got = pf.ancf_profile(psi, ne, mu, F, None if aug == "default" else float(aug), tmp, space)
                        print(f"[profile] ANCF {ne} el., mu {mu:g}, augmentation {aug}, pressure {space or 'default'}: "
                              + ("done" if got else "did not reach the level"), flush=True)
                        rows += got
                        if got:
                            break
    if args.merge and os.path.exists(path):
        keys = {(r["model"], r["variant"], r["resolution"], float(r["load_N"])) for r in rows}
        rows = [r for r in pf.read(path) if (r["model"], r["variant"], r["resolution"], float(r["load_N"])) not in keys] + rows
    pf.write(path, rows)


def spaces(args) -> list:
    """The pressure spaces of the ANCF columns (None: the default; else rep.SPACES names)."""
    names = [n.strip() for n in args.ancf_spaces.split(";") if n.strip()]
    return [None if n == "default" else n for n in names]


# ============================================================================================
# Driver
# ============================================================================================
def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--psi", default="45,0", help="pretwist angles [deg]")
    ap.add_argument("--mu", type=float, default=0.3, help="friction coefficient")
    ap.add_argument("--h", default="2e-3,1.4e-3,1.15e-3", help="solid mesh sizes [m] at the first pretwist, coarse to fine")
    ap.add_argument("--h-more", default="2e-3,1.4e-3", help="solid mesh sizes at the other pretwists")
    ap.add_argument("--stick", type=float, default=100.0, help="solid stick stiffness k in mu_max/h")
    ap.add_argument("--elements", default="4,8,16", help="ANCF elements per subtendon")
    ap.add_argument("--ancf-augmentations", default="default,10,0.1",
                    help="ANCF augmentation factors c of contact.tangential ('default': the law's, 1)")
    ap.add_argument("--ancf-spaces", default="default",
                    help="ANCF pressure spaces separated by ';': 'default' (quadratic along × linear across) and/or "
                         + ", ".join(f"'{n}'" for n in rep.SPACES))
    ap.add_argument("--max-increment", type=float, default=50.0, help="largest solid load increment [N]")
    ap.add_argument("--free-zone", type=float, default=0.0,
                    help="a diagnostic [m]: the runs without friction below x = this (solid: coarsest mesh only)")
    ap.add_argument("--selftest", action="store_true", help="only the FD check of the friction tangent")
    ap.add_argument("--no-selftest", action="store_true")
    ap.add_argument("--no-checks", action="store_true", help="skip the regularisation/slip/increment checks")
    ap.add_argument("--no-solid", action="store_true", help="only the ANCF columns")
    ap.add_argument("--no-ancf", action="store_true", help="only the solid")
    ap.add_argument("--merge", action="store_true", help="keep the CSV rows this run does not redo")
    ap.add_argument("--profiles", default="100", help="load levels [N] of the pressure/friction profiles "
                    "(solid h = the coarsest mesh, mu = 0 and mu; ANCF at each element count; '' for none)")
    ap.add_argument("--replot", action="store_true", help="figure and page section from the CSV")
    ap.add_argument("--out", default=os.path.join(vsc.ROOT, "docs"))
    args = ap.parse_args(argv)
    unknown = [n for n in spaces(args) if n is not None and n not in rep.SPACES]
    if unknown:
        print(f"verify_solid_friction: --ancf-spaces: unknown {unknown}; known: default, {', '.join(rep.SPACES)}",
              file=sys.stderr)
        return 2
    paths = rep.Paths(args.out)
    if args.replot:
        page.finish(paths, rep.read_csv(paths.csv), {})
        return 0
    vsc.vs._import_stack()
    t_start = time.perf_counter()
    secs = vsc.tendon_sections()
    rows = rep.read_csv(paths.csv) if args.merge and os.path.exists(paths.csv) else []

    def save(new):
        nonlocal rows
        keys = {rep.row_key(r) for r in new}
        rows = [r for r in rows if rep.row_key(r) not in keys] + new
        rep.write_csv(paths.csv, rows)

    if not args.no_selftest:
        print("[solid-friction] friction tangent against finite differences", flush=True)
        save(rep.fd_rows(selftest_fd(secs)))
        if args.selftest:
            page.finish(paths, rows, {"argv": " ".join(sys.argv[1:])})
            return 0
    psis = [float(p) for p in args.psi.split(",") if p.strip()]
    hs = [float(h) for h in args.h.split(",")]
    mu = args.mu
    zone = args.free_zone
    for psi in psis:
        for h in (hs if psi == psis[0] else [float(x) for x in args.h_more.split(",")])[:1 if zone else None]:
            if args.no_solid:
                break
            print(f"[solid] psi {psi:g}, mu {mu:g}, h {h * 1e3:.2f} mm, stick {args.stick:g}"
                  + (f", no friction below x = {zone * 1e3:g} mm" if zone else ""), flush=True)
            r = run_solid(secs, psi, h, mu, args.stick, max_increment=args.max_increment, free_zone=zone)
            save(rep.solid_rows(r, psi, mu, zone_label(f"stick {args.stick:g}", zone)))
        if not args.no_checks and not args.no_solid and not zone and psi == psis[0]:
            h = hs[0]
            for label, kw in ((f"stick {10 * args.stick:g}", {"stick": 10 * args.stick}),
                              ("slip closest", {"slip": "closest"}),
                              ("increments 10 N", {"max_increment": 10.0})):
                print(f"[solid] check {label}: psi {psi:g}, h {h * 1e3:.2f} mm", flush=True)
                opt = {"stick": args.stick, "max_increment": args.max_increment} | kw
                save(rep.solid_rows(run_solid(secs, psi, h, mu, **opt), psi, mu, label))
        if args.no_ancf:
            continue
        with tempfile.TemporaryDirectory(prefix="solid_friction_") as tmp:
            for space, aug in ((s, a) for s in spaces(args) for a in args.ancf_augmentations.split(",")):
                c = None if aug == "default" else float(aug)
                for ne in [int(e) for e in args.elements.split(",")]:
                    a = run_ancf(psi, ne, mu, c, tmp, zone, space)
                    last = a["levels"][-1] if a["levels"] else None
                    print(f"[ancf] psi {psi:g}, {ne} el., augmentation {aug}, pressure {space or 'default'}: "
                          + (f"{last['load']:g} N, soleus u_x {1e3 * last['u']['soleus']:.5f} mm" if last else "")
                          + (f", {a['wall']:.0f} s" if a["ok"] else f" FAILED ({a['msg']})"), flush=True)
                    save(rep.ancf_rows(a, mu))
    levels = [float(F) for F in args.profiles.split(",") if F.strip()] if not zone else []
    if levels:
        profiles(secs, args, levels, psis[0])
    page.finish(paths, rows, {"argv": " ".join(sys.argv[1:]), "total": time.perf_counter() - t_start})
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except vsc.ContactError as exc:
        print(f"verify_solid_friction: {exc}", file=sys.stderr)
        sys.exit(1)
