"""The friction solid's runs, its finite-difference check and the profile and space studies."""
from __future__ import annotations

import os
import tempfile

import numpy as np

from ancf_verify.contact.problem import Problem
from ancf_verify.contact.solid import run_solid as contact_run_solid, tendon_problem
from ancf_verify.contact.tendon import AXIS, LENGTH, LOADS
from ancf_verify.friction.model import FrictionProblem


def run_solid(secs, psi: float, h: float, mu: float, stick: float, slip: str = "partner",
              max_increment: float = 50.0, loads=LOADS, log=print, free_zone: float = 0.0, local=None) -> dict:
    """One solid run with friction (verify_solid_contact.run_solid with FrictionProblem;
    ``free_zone`` > 0, a diagnostic: no friction at slave points below x = free_zone [m];
    ``local``: a contact.mesh.LocalSize, h then being the bulk size)."""
    r = contact_run_solid(secs, psi, "sliding", h, loads=list(loads), max_increment=max_increment, log=log,
                          problem_class=FrictionProblem, mu=mu, stick=stick, slip=slip, free_zone=free_zone,
                          local=local)
    r["local"] = local
    return r


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
        P, _ = tendon_problem(secs, psi, h, "sliding", problem_class=FrictionProblem, mu=0.3, slip=slip)
        P.set_load(60.0)
        u = sliding_state(P)
        z = P.ak_all * (1.0 + 0.6 * rng.random(P.nc)) * 1e6 / P.ks
        x = P.positions(u)
        c0 = Problem.residual(P, u, z, False)[2]
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


def sliding_state(P) -> np.ndarray:
    """verify_solid_contact.selftest_fd's deformed state: stretch, 2 mm soleus slide, twist."""
    X = P.X
    dm = P.V.dofmap.list.array.reshape(-1, 10)
    sol = np.unique(dm[P.ct.indices[P.ct.values == 1]].ravel())
    U = np.zeros_like(X)
    U[:, 0] = 0.005 * X[:, 0]
    U[sol, 0] += 0.03 * X[sol, 0]
    U[:, 1] += 0.01 * (X[:, 0] / LENGTH) * (X[:, 2] - AXIS[1])
    U[:, 2] -= 0.01 * (X[:, 0] / LENGTH) * (X[:, 1] - AXIS[0])
    return U.ravel() * P.mask


def profiles(secs, args, levels: list, psi: float) -> None:
    """Pressure and friction along the tendon (solid_friction_profiles.py): the solid on the
    coarsest mesh, frictionless and with μ; the ANCF columns (default augmentation, then the
    others where it fails), frictionless and with μ; written to solid_friction_profiles.csv."""
    from ancf_verify.friction.profiles import ancf_profile, read, solid_profile, write
    path = os.path.join(args.out, "solid_friction_profiles.csv")
    rows = []
    h = args.h[0]
    with tempfile.TemporaryDirectory(prefix="solid_friction_profiles_") as tmp:
        for F in levels:
            for mu in (0.0, args.mu):
                if not args.no_solid:
                    print(f"[profile] solid, mu {mu:g}, h {h * 1e3:.2f} mm, {F:g} N", flush=True)
                    rows += solid_profile(secs, psi, h, mu, F, args.stick)
                for space, ne in ((s, e) for s in spaces(args) for e in args.elements):
                    for aug in (args.ancf_augmentations.split(",") if mu else ["default"]):
                        got = ancf_profile(psi, ne, mu, F, None if aug == "default" else float(aug), tmp, space,
                                           element=args.element or None)
                        print(f"[profile] ANCF {ne} el., mu {mu:g}, augmentation {aug}, pressure {space or 'default'}: "
                              + ("done" if got else "did not reach the level"), flush=True)
                        rows += got
                        if got:
                            break
    if args.merge and os.path.exists(path):
        keys = {(r["model"], r["variant"], r["resolution"], float(r["load_N"])) for r in rows}
        rows = [r for r in read(path) if (r["model"], r["variant"], r["resolution"], float(r["load_N"])) not in keys] + rows
    write(path, rows)


def spaces(args) -> list:
    """The pressure spaces of the ANCF columns (None: the default; else rep.SPACES names)."""
    names = [n.strip() for n in args.ancf_spaces.split(";") if n.strip()]
    return [None if n == "default" else n for n in names]
