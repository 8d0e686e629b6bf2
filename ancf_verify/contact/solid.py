"""The tendon as a contact problem: build, solve along the load levels, end-section centroids."""
from __future__ import annotations

import time

import numpy as np

from ancf_verify.contact.mesh import interface_tag, tendon_mesh
from ancf_verify.contact.problem import Problem
from ancf_verify.contact.tendon import AXIS, ContactError, INTERFACES, KBULK, LENGTH, LOADS, MU, SHORT


# ============================================================================================
# The tendon: solid runs
# ============================================================================================
def centroid_points(secs, psi: float, bodies=(0, 1, 2)) -> np.ndarray:
    """Reference end-section centroids a + R(psi)(c - a) on x = L."""
    from ancf_petsc.physics.geometry import place
    return np.vstack([place(np.array([LENGTH]), secs[b].centroid[None, :], LENGTH, psi, AXIS)
                      for b in bodies])


def tendon_problem(secs, psi: float, h: float, law: str | None, bodies=(0, 1, 2), loads_on=(0,),
                   layered: bool = True, problem_class=None, root: str = "clamped", local=None, **kw):
    """Mesh (timed) and Problem of the tendon: roots ``root`` (clamped or plane:
    ancf_verify.roots), end traction 1 N x load factor on
    the end faces of ``loads_on``, contact on the interfaces between the chosen bodies
    (``problem_class``: a Problem subclass taking the same arguments, e.g. with friction;
    ``local``: a contact.mesh.LocalSize, finer elements around one interface)."""
    t0 = time.perf_counter()
    msh, ct, ft = tendon_mesh(secs, h, psi, bodies, layered, local)
    t_mesh = time.perf_counter() - t0
    mats = {b + 1: (MU[b], KBULK) for b in bodies}
    dirich = [(10 + b, root) for b in bodies]
    tr = {20 + b: (1.0, 0.0, 0.0) for b in loads_on}
    ifs = []
    if law:
        ifs = [(cv, interface_tag(secs, s, cv), interface_tag(secs, m, cv)) for cv, s, m in INTERFACES
               if s in bodies and m in bodies]
    P = (problem_class or Problem)(msh, ct, ft, mats, dirich, tr, ifs, law=law if ifs else None, **kw)
    return P, t_mesh


def run_solid(secs, psi: float, law: str | None, h: float, loads=LOADS, bodies=(0, 1, 2), log=print,
              max_increment: float = 50.0, **kw) -> dict:
    """One solid run over the load levels: per level the end-centroid u of each body, the soleus
    end-face mean, Newton iterations, cumulative wall time and the contact diagnostics."""
    t0 = time.perf_counter()
    P, t_mesh = tendon_problem(secs, psi, h, law, bodies, **kw)
    pts = centroid_points(secs, psi, bodies)
    levels = []
    t_solve0 = time.perf_counter()

    def on_level(level, its):
        u = [P.point_values(pts[i:i + 1], b + 1)[0] for i, b in enumerate(bodies)]
        rec = {"load": float(level), "its": its, "wall": time.perf_counter() - t_solve0,
               "u": {SHORT[b]: u[i] for i, b in enumerate(bodies)},
               "face": P.face_mean(20)}
        rec.update(P.gap_report())
        levels.append(rec)
        if log:
            extra = ""
            if "g_max" in rec:
                extra = (f", |g-g0| max {rec['g_max'] * 1e6:.2f} um, p [{rec['p_min'] / 1e6:+.2f}, "
                         f"{rec['p_max'] / 1e6:+.2f}] MPa, active {rec['active']}/{rec['nc']}, "
                         f"off-master points {rec['off']}/{rec['nq']}")
            if rec.get("friction"):
                extra += ", friction x " + ", ".join(f"{k} {v['force_x']:+.4f} N" for k, v in rec["friction"].items())
            others = "".join(f", {SHORT[b]} u_x {1e6 * u[i][0]:+.4f} um" for i, b in enumerate(bodies) if i)
            log(f"    {level:5.0f} N: soleus u_x {1e3 * u[0][0]:.6f} mm{others}, {its} its, "
                f"{rec['wall']:.1f} s{extra}")

    ok, msg = True, ""
    try:
        P.solve_path(list(loads), on_level=on_level, max_increment=max_increment, log=log)
    except ContactError as exc:
        ok, msg = False, str(exc)
    return {"psi": psi, "law": law or "free", "h": h, "dofs": P.ndof, "nc": P.nc, "levels": levels,
            "ok": ok, "msg": msg, "t_mesh": t_mesh, "wall": time.perf_counter() - t_solve0, "penalty": P.penalty,
            "stats": dict(P.stats), "ks": P.ks, "h_mean": P.h, "t_total": time.perf_counter() - t0}
