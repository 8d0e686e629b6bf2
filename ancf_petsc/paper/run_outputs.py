"""What ``ancf-report --existing`` shows of a run that is not the paper's model: its probes with
their own units, the force it carried (the loads, or a prescribed end's reaction under
displacement control), how far the subtendons moved against each other (first − second in
config order) and, for a contact run, slip and pressure along the tendon."""
from __future__ import annotations

import os

import numpy as np

from .. import viz
from ..io.groups import PROBE_UNITS
from ..io.reader import read_contact

#: how a probe's change is shown: a displacement (r, or the section mean) as u in mm, another
#: vector's change in its own unit (io.groups.PROBE_UNITS)
SHOWN = {"r": "u", "mean": "section-mean u"}
#: a probe's y or z displacement is shown where it reaches this share of its largest component
MOVED = 1e-3
#: slip and pressure are drawn at up to this many levels (the last among them)
SLIP_LEVELS = 4


def probe_vectors(config: dict) -> dict[str, str]:
    """Probe name → its nodal vector (``r`` unless the config says otherwise)."""
    return {p["name"]: p.get("vector", "r") for p in config.get("probes", []) or []
            if isinstance(p, dict) and "name" in p}


def mm_cell(value: float) -> str:
    """A length in mm for a table: 5 decimals, or 4 significant digits below 0.01 mm (a fascicle's
    displacements of 20 nm read -0.00002, of 4 nm -0.00000, at 5 decimals)."""
    return f"{value:.5f}" if value == 0.0 or abs(value) >= 0.01 or not np.isfinite(value) else f"{value:.4g}"


def moved_components(steps: list[dict], name: str) -> list[int]:
    """The components of probe ``name``'s displacement shown: x, and y or z where they reach
    ``MOVED`` of its largest component at some level (a cantilever's u_z was left out: the table
    showed u_x alone, -10 mm, of a tip that moved 40 mm down)."""
    d = np.array([st["probes"][name]["displacement"] for st in steps if name in st.get("probes", {})],
                 dtype=float).reshape(-1, 3)
    big = np.abs(d).max(axis=0) if len(d) else np.zeros(3)
    return [0] + [k for k in (1, 2) if big[k] > MOVED * big.max()]


def probe_markdown(summary: dict, config: dict) -> list[str]:
    """A table of every probe per level: u [mm] of a position (r, mean), x and the components it
    moves along (``moved_components``), the three components of a direction vector's change [1]
    (r_y, r_z) or of a curvature vector's [1/m]."""
    steps = summary["steps"]
    names = sorted({p for st in steps for p in st.get("probes", {})})
    if not names:                       # a run without probes: no table (not an empty one)
        return []
    vectors = probe_vectors(config)
    heads, cells = [], []
    for name in names:
        vector = vectors.get(name, "r")
        position = PROBE_UNITS.get(vector, "m") == "m"
        scale = 1e3 if position else 1.0
        shown = moved_components(steps, name) if position else [0, 1, 2]
        if position:
            heads += [f"{name} {SHOWN.get(vector, 'u')}_{'xyz'[k]} [mm]" for k in shown]
        else:
            heads.append(f"{name} Δ{vector} (x, y, z) [{PROBE_UNITS[vector]}]")

        def value(st, k, name=name, scale=scale, position=position):
            if name not in st.get("probes", {}):
                return ""
            d = np.asarray(st["probes"][name]["displacement"], dtype=float) * scale
            return mm_cell(d[k]) if position else "(" + ", ".join(f"{x:.5g}" for x in d) + ")"
        cells += [lambda st, k=k, value=value: value(st, k) for k in (shown if position else [0])]
    lines = [level_head(steps) + " | ".join(heads) + " |", level_rule(steps) + "---:|" * len(heads)]
    lines += [f"| {level_cell(st)} | " + " | ".join(c(st) for c in cells) + " |" for st in steps]
    return lines


def timed(steps: list[dict]) -> bool:
    """Whether the levels are a load history's frames (summary ``frame`` and ``time`` [s])."""
    return bool(steps) and all("frame" in st and "time" in st for st in steps)


def level_head(steps: list[dict]) -> str:
    """The level columns' header: a history's frame and time [s], else the load factor."""
    return "| frame | time [s] | " if timed(steps) else "| load factor | "


def level_rule(steps: list[dict]) -> str:
    return "|---:|---:|" if timed(steps) else "|---:|"


def level_cell(step: dict) -> str:
    """A level's load factor, or a history frame's number and time [s] (two cells); for one
    reported past a gap of the load path also the level asked, for an unstable one its count."""
    asked = (step.get("passed_over") or {}).get("level")
    cell = f"{step['frame']} | {step['time']:g}" if "frame" in step and "time" in step else f"{step['load_factor']:g}"
    neg = step.get("negative_eigenvalues")
    return (cell + ("" if asked is None else f" (level {asked:g}, past a gap of the load path)")
            + (f" (unstable: {neg} negative tangent eigenvalue(s))" if neg else ""))


def level_words(step: dict) -> str:
    """A level in words: 'load factor 4', or a history's 'frame 4, t = 0.75 s'."""
    if "frame" in step and "time" in step:
        return f"frame {step['frame']}, t = {step['time']:g} s"
    return "load factor " + level_cell(step)


def moved_supports(config: dict, summary: dict | None = None) -> list[str]:
    """The names of the supports with a prescribed displacement (displacement control), as the
    run's ``reactions`` name them: the k-th support of the config is their k-th (one without a
    name is '<beam>.<node index>' there, e.g. 'slider.0' for node: first)."""
    bcs = config.get("boundary_conditions", []) or []
    steps = (summary or {}).get("steps") or [{}]
    names = list(steps[0].get("reactions") or {})
    out = []
    for k, bc in enumerate(bcs):
        if isinstance(bc, dict) and "displacement" in bc:
            given = bc.get("name") or f"{bc.get('beam')}.{bc.get('node', '')}"
            out.append(names[k] if len(names) == len(bcs) else given)
    return out


#: an x-sum of the reactions within this share of their magnitudes is rounding: no load along x
REACTION_ROUNDING = 1e-8


def force_axis(summary: dict, config: dict) -> tuple[np.ndarray, str]:
    """The force each level carried and its label: the x-reactions of the moved supports under
    displacement control, else the x-sum of the loads applied at each level (minus the supports'
    reactions, by equilibrium: curves, history columns and loads anywhere included; a beam's
    ``subtendons`` end force also holds the reactions of supports at its last node), else (files
    without reactions) the load factor times the loads' x-sum (a load curve: the load factor)."""
    steps = summary["steps"]
    moved = [n for n in moved_supports(config, summary) if all(n in st.get("reactions", {}) for st in steps)]
    if moved:
        return (np.array([sum(st["reactions"][n][0] for n in moved) for st in steps]),
                f"reaction of {', '.join(moved)} along x [N]")
    if steps and all(st.get("reactions") for st in steps):
        rx = [np.array([r[0] for r in st["reactions"].values()]) for st in steps]
        fx = -np.array([x.sum() for x in rx])
        fx[np.abs(fx) <= REACTION_ROUNDING * max(np.abs(x).sum() for x in rx)] = 0.0
        if np.any(fx != 0.0):
            return fx, "applied load along x [N]"
    loads = [ld for ld in config.get("loads", []) or [] if isinstance(ld, dict)]
    lam = np.array([st["load_factor"] for st in steps])
    if loads and not any("curve" in ld for ld in loads):
        fx = sum(float((ld.get("force") or ld.get("traction_force") or [0.0])[0]) for ld in loads)
        if fx != 0.0:
            return lam * fx, "applied load along x [N]"
    return lam, "load factor"


def interface_markdown(summary: dict, config: dict) -> list[str]:
    """Per level the force (``force_axis``) and each pair's u_first − u_second at x = L [mm];
    nothing for a run without interfaces or moved supports."""
    steps = summary["steps"]
    pairs = list(dict.fromkeys(p for st in steps for p in st.get("displacement_differences", {})))
    if not pairs and not moved_supports(config, summary):
        return []
    force, label = force_axis(summary, config)
    heads = [label] + [f"{p.replace('|', ' − ')} [mm]" for p in pairs]
    intro = ("How far the subtendons moved against each other (`displacement_differences`: u_x of the first "
             "beam's centroid line minus the second's at x = L, first and second in config order):" if pairs
             else "The force of each level (displacement control):")
    lines = ["", intro, "", level_head(steps) + " | ".join(heads) + " |", level_rule(steps) + "---:|" * len(heads)]
    for st, f in zip(steps, force):
        dd = st.get("displacement_differences", {})
        cells = [f"{f:.6g}"] + [mm_cell(1e3 * dd[p]["end"]) if p in dd else "" for p in pairs]
        lines.append(f"| {level_cell(st)} | " + " | ".join(cells) + " |")
    return lines


def support_markdown(summary: dict) -> list[str]:
    """The supports at the last level: the force each exerts on its beam's r [N] and its moment
    about the node's section centroid [N m] (summary ``reactions``, ``reaction_moments``); nothing
    for a run that wrote no moments."""
    last = (summary.get("steps") or [{}])[-1]
    forces, moments = last.get("reactions") or {}, last.get("reaction_moments") or {}
    if not moments:
        return []
    lines = ["", f"The supports at the last level ({level_words(last)}): force on the beam [N] and moment "
             "about the node's section centroid [N m]:", "",
             "| support | F_x | F_y | F_z | M_x | M_y | M_z |", "|---|" + "---:|" * 6]
    for name, m in moments.items():
        cells = list(forces.get(name, [np.nan] * 3)) + list(m)
        lines.append(f"| {name} | " + " | ".join(f"{x:.6g}" for x in cells) + " |")
    return lines


def run_figures(directory: str, summary: dict, config: dict, out: str,
                stem: str | None = None) -> list[str]:
    """A load history's figure over its frames (viz/history.py: muscle forces, strains, end
    differences against time), the run's force–elongation and differences chart and, with contact
    fields in results.h5, slip and pressure along the tendon; the PNG paths (files named after
    the run, or ``stem``)."""
    steps = summary.get("steps", [])
    pairs = list(dict.fromkeys(p for st in steps for p in st.get("displacement_differences", {})))
    name = stem or summary.get("name") or os.path.basename(os.path.normpath(directory))
    history = timed(steps) and all("subtendons" in st for st in steps)
    made = [viz.plot_history(summary, os.path.join(out, f"{name}_history.png"),
                             title=f"{name}: the load history's frames")] if history else []
    if not steps or (not pairs and not moved_supports(config, summary)):
        return made
    force, label = force_axis(summary, config)
    vectors = probe_vectors(config)
    elong = {p: np.array([st["probes"][p]["displacement"][0] for st in steps])
             for p in vectors if vectors[p] in ("r", "mean") and all(p in st["probes"] for st in steps)}
    diffs = {p: np.array([st["displacement_differences"][p]["end"] for st in steps]) for p in pairs
             if all(p in st.get("displacement_differences", {}) for st in steps)}
    made += [viz.plot_force_and_differences(force, label, elong, diffs, os.path.join(out, f"{name}_force.png"),
                                            title=f"{name}: force and subtendon displacement differences")]
    h5 = os.path.join(directory, "results.h5")
    itfs = summary.get("contact_interfaces") or []
    if itfs and os.path.exists(h5):
        picks = sorted({int(round(k)) for k in np.linspace(0, len(steps) - 1, min(SLIP_LEVELS, len(steps)))})
        levels = [read_contact(h5, k + 1) for k in picks]
        made.append(viz.plot_slip(levels, viz.interface_labels(itfs), os.path.join(out, f"{name}_slip.png"),
                                  tuple(range(len(itfs))), float(config.get("geometry", {}).get("length", 0.0)),
                                  title=f"{name}: slip and contact pressure along the tendon",
                                  level_label="frame {:g}" if timed(steps) else "load factor {:g}"))
    return made
