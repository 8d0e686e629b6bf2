"""Contact results of one rank at a state: per-interface gap and pressure statistics (combined over
the ranks by the caller, ``GAP_COLUMNS`` says how) and per-point fields for the output."""
from __future__ import annotations

import numpy as np

from .interfaces import held_ends, supported_ends
from .kinks import TURN_NOTE, turn_notes
from .oscillation import OSCILLATION_NOTE, oscillation_notes
from .state import ContactState

#: per-interface statistics of ``gap_sums``: (name, how ranks combine it)
GAP_COLUMNS = (("max_gap", "max"), ("max_penetration", "max"), ("sum_sq_gap", "sum"), ("valid_points", "sum"),
               ("max_weighted_gap", "max"), ("open_area", "sum"), ("area", "sum"),
               ("max_pressure", "max"), ("normal_force", "sum"), ("pressing_force", "sum"),
               ("tension_force", "sum"), ("points", "sum"), ("past_ends_force", "sum"),
               ("max_penetration_along", "max"))


#: a unilateral interface whose largest pointwise penetration exceeds this share of the smaller of
#: its two sections' smallest widths draws a warning (issue 42: the weighted gaps hold while the
#: contact points themselves interpenetrate; 1 % is 27 µm on the paper's Type III outlines)
PENETRATION_SHARE = 0.01


def describe(c) -> list[str]:
    """The ``Contact`` c in the run's header: laws, multipliers, points, supported ends,
    interfaces."""
    ka, kc = c.space.degrees
    laws = "; ".join([c.law.describe()] + ([t.describe() for t in c.terms] or ["frictionless"]))
    lines = [f"contact: {laws}; Lagrange multipliers (pressure of degree {ka} along the beam x {kc} "
             f"across the interface per element, {c.n_multipliers} in all); {c.points.n_points} points "
             f"({c.spec.axial_points} axial x {c.spec.curve_points} per curve piece); unknowns scaled "
             f"by k_s = {c.stiffness:.4g} N/m", "  " + ends_line(c)]
    for itf in c.interfaces:
        lines.append(f"  interface {itf.name}: {itf.n_points} points on {itf.a.name}, "
                     f"projected onto {itf.b.name}")
    return lines


def ends_line(c) -> str:
    """The supported ends' rules (``contact.projection.supported_ends`` and, for friction,
    ``contact.tangential.supported_ends``) and how many interface ends each folds."""
    normal = int(supported_ends(c.model, c.interfaces, c.spec.supported_ends).sum())
    line = (f"supported ends: pressure {c.spec.supported_ends} ({normal} clamped interface end(s) folded "
            "into their neighbours)")
    if any(t.multipliers for t in c.terms):
        tang = int(held_ends(c.model, c.interfaces, c.spec.tangential).sum())
        line += (f"; tangential {c.spec.tangential.supported_ends} ({tang} end(s) where both bodies' "
                 "r is held folded)")
    return line


def report_columns(c) -> tuple:
    """Per-interface statistics of ``gap_sums`` of the ``Contact`` c: (name, how ranks combine
    it), ``GAP_COLUMNS`` then each term's."""
    return GAP_COLUMNS + tuple(col for t in c.terms for col in t.columns)


def gap_sums(c, st: ContactState) -> np.ndarray:
    """Per interface (rows) the local parts of ``report_columns`` of the ``Contact`` c at its
    evaluation st.  The forces are the points' τ_p (with their fade weights: what acts on the
    beams), not Σ_k λ_k A_k: past the ends a function's points weigh less than its A_k."""
    out = np.zeros((len(c.interfaces), len(report_columns(c))))
    if len(c.local) == 0:
        return out
    pr = st.pr
    itf_p = c.points.itf[c.local]
    itf_m = c.space.interface[c.mults]
    area = c.space.area[c.mults] * c.owned        # each multiplier counted once
    lam = pressure_coefficients(c, st)
    over = pr.valid & c.projector.on_surface(c.local, pr.eB, pr.xiB, pr.tB)    # penetration: only there
    for k in range(len(c.interfaces)):
        on, m = itf_p == k, itf_m == k
        v = on & pr.valid
        m = m & c.owned
        act = m & st.active
        out[k] = [np.abs(pr.g[v]).max(initial=0.0), np.max(-pr.g[on & over], initial=0.0),
                  float(np.sum(pr.g[v] ** 2)), v.sum(),
                  np.abs(st.gbar[act]).max(initial=0.0), area[m & ~st.active].sum(), area[m].sum(),
                  lam[m].max(initial=0.0), float(st.tau[v].sum()),
                  float(np.maximum(st.tau[v], 0.0).sum()), float(np.minimum(st.tau[v], 0.0).sum()),
                  on.sum(), float(np.abs(st.tau[v & ~over]).sum()),
                  along_penetration(c, pr.g, v & over)] + [
                  x for t in c.terms for x in t.sums(c, st, on)]
    return out


def along_penetration(c, g: np.ndarray, sel: np.ndarray) -> float:
    """The largest penetration at a station (A element and axial point) of the local points
    ``sel`` that none of its points across the interface opens: −max g over the station, the
    part of a penetration that no tilt across explains (0 where every station has an open point)."""
    if not sel.any():
        return 0.0
    idx = c.local[sel]
    _, station = np.unique(np.column_stack([c.points.seg[idx], c.points.xi[idx]]), axis=0,
                           return_inverse=True)
    top = np.full(station.max() + 1, -np.inf)
    np.maximum.at(top, station.ravel(), g[sel])
    return float(max(0.0, -top.min()))


def pressure_coefficients(c, st: ContactState) -> np.ndarray:
    """λ_k [Pa] of the local multipliers (zero where inactive)."""
    return c.stiffness * st.z * st.active / c.space.area[c.mults]


def gap_report(contact, sums: np.ndarray) -> dict:
    """Per-interface statistics from (rank-combined) ``gap_sums``, keyed by the interfaces'
    names "curve (first|second)"; the beam carrying the points is ``points_on``.  Signs and
    units: docs/running.md, "Contact outputs"."""
    out = {}
    for k, itf in enumerate(contact.interfaces):
        c = dict(zip([n for n, _ in report_columns(contact)], sums[k]))
        nv = c["valid_points"]
        absolute = c["pressing_force"] - c["tension_force"]        # Σ|τ_p|
        out[itf.name] = {"points_on": itf.a.name,
                         "max_gap": c["max_gap"], "max_penetration": c["max_penetration"],
                         "max_penetration_along": c["max_penetration_along"],
                         "rms_gap": float(np.sqrt(c["sum_sq_gap"] / nv)) if nv else 0.0,
                         "max_weighted_gap": c["max_weighted_gap"],
                         "open_share": c["open_area"] / c["area"] if c["area"] else 0.0,
                         "max_pressure": c["max_pressure"], "normal_force": c["normal_force"],
                         "pressing_force": c["pressing_force"], "tension_force": c["tension_force"],
                         "points": int(c["points"]),
                         "past_ends_force": c["past_ends_force"],
                         "past_ends_share": (c["past_ends_force"] / absolute if absolute else 0.0)}
        for term in contact.terms:
            out[itf.name].update(term.report(c, itf.sign))
    return out


def output_signs(c, interface: np.ndarray) -> np.ndarray:
    """Per entry of ``interface`` (interface ids) the ``Interface.sign`` of the ``Contact`` c:
    what turns a quantity of A against B into the outputs' first against second."""
    return np.array([itf.sign for itf in c.interfaces])[interface] if len(interface) else np.zeros(0)


def point_fields(c, st: ContactState, q0_of) -> dict:
    """Per local point: id, interface, current and reference position on A (the beam carrying
    the points), its reference area w_p [m²] (pressure × area is the point's force: the
    pressure includes the point's weight),
    gap, pressure, slip u_first − u_second [m] of the two material points in contact now (the
    reference position of the second beam's minus the first's: first and second in config
    order) and the projection state (e_B, ξ_B, t_B); per owned multiplier: id, pressure
    coefficient λ [Pa] and status.  ``q0_of(elements)`` gives reference nodal vectors."""
    pr, idx = st.pr, c.local
    if len(idx):
        X0A = np.einsum("pa,pai->pi", pr.NA, q0_of(c.points.eA[idx]))
        X0B = np.einsum("pa,pai->pi", pr.NB, q0_of(pr.eB))
    else:
        X0A = X0B = np.zeros((0, 3))
    pressure = np.where(pr.valid, st.tau / c.points.w[idx], 0.0)
    own = c.owned
    terms = {k: v for t in c.terms for k, v in t.fields(c, st).items()}
    return terms | {"id": idx, "interface": c.points.itf[idx], "x": st.xA, "x0": X0A,
                    "area": c.points.w[idx],
            "gap": pr.g * pr.valid, "pressure": pressure,
            "slip": (output_signs(c, c.points.itf[idx]) * pr.valid)[:, None] * (X0B - X0A),
            "projection": np.column_stack([pr.eB, pr.xiB, pr.tB]) if len(idx) else np.zeros((0, 3)),
            "multiplier_id": c.mults[own],
            "multiplier_pressure": pressure_coefficients(c, st)[own],
            "multiplier_active": st.active[own]}


#: what marks a warning about the last level (a restart drops the stopped run's: ``made_at_the_end``)
LAST_LEVEL = "at the last level"


#: the start of ``path_notes``' line
PATH_NOTE = "note: Coulomb friction's answer follows the load path"


def made_at_the_end(note: str) -> bool:
    """Whether a warning line is one made at the end of a run (``penetration_warnings`` about its
    last level, ``path_notes``, ``turn_notes`` and ``oscillation_notes`` about its levels): a
    restarted run makes it again."""
    return ((note.startswith("warning: contact interface ") and (LAST_LEVEL in note or OSCILLATION_NOTE in note))
            or note.startswith(PATH_NOTE) or note.startswith(TURN_NOTE))


def end_notes(c, steps: list[dict]) -> list[str]:
    """The lines a run's end adds to its warnings (``steps``: summary.json's, at least one):
    penetration at the last level, a friction path chosen by the solver, B's normal turning at
    element boundaries (kinks.turn_notes), a pressure oscillating under friction
    (oscillation.oscillation_notes)."""
    return (penetration_warnings(c, steps[-1].get("contact", {})) + path_notes(c, steps)
            + turn_notes(c, steps) + oscillation_notes(c, steps))


def path_notes(c, steps: list[dict]) -> list[str]:
    """One line if the ``Contact`` c has friction (bounds that follow the state) and levels of
    ``steps`` (summary.json's) were reached through cut-backs or Tresca solves: their increments
    were the solver's choice, and near a stick–slip change whether a solve fails follows rounding
    (docs/gait.md, "Friction histories and the increment": the locked-in soleus displacement of
    the 13-frame stride is 0.11725 or 0.11502 mm by that alone), so another number of ranks, a
    restart or other options may end on another valid state."""
    levels = [s["load_factor"] for s in steps if s.get("cutbacks") or s.get("tresca_solves")]
    if not levels or not any(t.bounded for t in c.terms):
        return []
    shown = ", ".join(f"{x:g}" for x in levels[:5]) + (", ..." if len(levels) > 5 else "")
    return [f"{PATH_NOTE}: {len(levels)} level(s) ({shown}) were reached through cut-backs or Tresca "
            "solves, increments the solver chose; near a stick-slip change whether a solve fails follows "
            "rounding, so another number of ranks, a restart or other options may take other increments "
            "and end on another valid state (docs/gait.md, \"Friction histories and the increment\"); a "
            "smaller solver.max_increment makes cut-backs rarer"]


def penetration_warnings(c, report: dict) -> list[str]:
    """One warning line, if the law of the ``Contact`` c lets the bodies separate (unilateral),
    for the interfaces whose ``max_penetration`` in ``report`` (a level's ``gap_report``: the
    largest −gap at a contact point on the partner's surface) is above ``PENETRATION_SHARE`` of
    the smaller smallest section width of their two beams: the deepest named with its depth, the
    others after it (a bundle's interfaces alike, one line for all); none for the other laws
    (their weighted gaps are zero both ways: a pointwise gap of either sign is their
    discretisation's)."""
    if not c.law.decides_activity:          # gaps held at zero both ways (sliding)
        return []
    deep = []
    for itf in c.interfaces:
        depth = report.get(itf.name, {}).get("max_penetration", 0.0)
        width = min(itf.a.section.smallest_width, itf.b.section.smallest_width)
        if depth > PENETRATION_SHARE * width:
            deep.append((depth, width, itf.name))
    if not deep:
        return []
    deep.sort(key=lambda d: -d[0])
    depth, width, name = deep[0]
    others = ""
    if len(deep) > 1:
        names = ", ".join(n.split(" (")[0] for _, _, n in deep[1:])
        others = (f" and {len(deep) - 1} other(s) ({names}: {deep[-1][0] * 1e6:.3g}-"
                  f"{deep[1][0] * 1e6:.3g} um)")
    along = report[name].get("max_penetration_along", 0.0)
    return [f"warning: contact interface {name}{others}: the bodies interpenetrate at the contact points by "
            f"up to {depth * 1e6:.3g} um {LAST_LEVEL}, above {PENETRATION_SHARE:.0%} of the thinner section "
            f"({width * 1e3:.3g} mm wide): the unilateral law holds each pressure function's weighted gap "
            ">= 0, not each point's: "
            + (_ALONG.format(along * 1e6) if along >= 0.5 * depth else
               _ACROSS + (FRICTION_ACROSS if any(t.bounded for t in c.terms) else ""))
            + "; see docs/contact.md, \"Pointwise penetration\""]


#: the cause and remedy of a penetration that tilts across the interface (one edge in, one out)
_ACROSS = ("a function spanning the interface across lets one edge cross while the other opens; local "
           "functions across (contact.projection.curve_spans: 4 with contact.curve_points: 4) held the "
           "points to 14 um on the paper's tendon at 10 and 400 N")

#: ... and of one that every point across shares (a contact concentrated along the beam: two
#: strips pressed at their tips, 2 / 4 / 8 elements: 36 / 10 / 2.3 um; curve_spans 4: 36.5 um)
_ALONG = ("{:.3g} um of it where every point across the interface penetrates: a function spans an "
          "element along the beam, so a contact concentrated along it (a loaded end, a point load) "
          "crosses between its functions there; more elements along reduce it (functions across do not)")


#: the penetration warning's remedy under Coulomb friction (measured 2026-12-07, the paper's tendon,
#: 4 elements, unilateral, mu 0.1 / 0.5: curve_spans 4, degree 0 on 5 spans and Bernstein 3 across
#: all failed at load factor 0.0006-0.0024 of the first 10 N level, 1 066-18 517 Newton iterations)
FRICTION_ACROSS = (" without friction; under Coulomb friction every richer pressure across tried "
                   "(curve_spans 4 or 5, curve: 3) failed at the first level, so none is known: read "
                   "max_penetration")
