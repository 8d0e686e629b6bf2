"""Plausibility of a model's sizes and of its first converged level: lengths written in
millimetres where the config means metres (``length: 70`` for 0.07) solve for hundreds of Newton
iterations and fail without a word.  Each check gives one warning line naming the key and the
likely unit mistake; the model is built and solved as given."""
from __future__ import annotations

import re

import numpy as np

__all__ = ["MAX_LENGTH", "MAX_WIDTH", "SLENDERNESS", "MAX_FIRST_STRAIN", "MIN_OVERFLOW_STRETCH",
           "fibre_warnings", "size_warnings", "strain_warning", "point_force_warnings"]

#: a tendon, fascicle or bar longer than this [m] is most likely given in mm
MAX_LENGTH = 5.0
#: a section wider than this [m] is most likely given in mm
MAX_WIDTH = 0.5
#: plausible range of a beam's length over the square root of its section area
SLENDERNESS = (1.0, 1000.0)
#: an axial strain beyond this (either sign) at the first converged level suggests wrong units
MAX_FIRST_STRAIN = 0.5
#: a fibre law whose exponential overflows (double precision) below this fibre stretch is warned
#: of: tendon fibres stretch by several per cent
MIN_OVERFLOW_STRETCH = 1.1
#: ln of the largest double: e^x is inf beyond it
LOG_MAX_DOUBLE = float(np.log(np.finfo(float).max))


def _section_key(spec, i: int) -> str:
    """The config key a beam's section dimensions come from."""
    bs = spec.beams[i].section
    if bs.curves is not None:            # inline outlines; a bundle's fascicles are written so
        bundle = re.fullmatch(r"fascicle\d+", spec.beams[i].name) is not None
        return "bundle.radius" if bundle else f"beams[{i}].section.curves"
    if bs.shape == "outline" and bs.file is None:
        return "geometry.sections"
    return f"beams[{i}].section" + (".file" if bs.file else "")


def size_warnings(spec, beams) -> list[str]:
    """Warnings (one line each) for a length or section sizes that look like millimetres
    (SI units: metres), else for a beam length / sqrt(area) outside ``SLENDERNESS``."""
    out = []
    L = spec.length
    if L > MAX_LENGTH:
        out.append(f"warning: geometry.length is {L:g} m (longer than {MAX_LENGTH:g} m): lengths are in "
                   f"metres (units: SI); if you meant {L:g} mm, write length: {L * 1e-3:g}")
    wide = [(i, b, 2.0 * float(np.max(b.section.extent))) for i, b in enumerate(beams)
            if 2.0 * float(np.max(b.section.extent)) > MAX_WIDTH]
    if wide:
        i, b, w = wide[0]
        more = f" (and {len(wide) - 1} more beam(s))" if len(wide) > 1 else ""
        out.append(f"warning: {_section_key(spec, i)}: the section of beam {b.name} is {w:g} m wide"
                   f"{more} (more than {MAX_WIDTH:g} m): section sizes are in metres (units: SI); "
                   f"if they are millimetres, divide them by 1000")
    if out:
        return out
    lo, hi = SLENDERNESS
    for i, b in enumerate(beams):
        s = L / np.sqrt(b.section.area)
        if not lo <= s <= hi:
            short = s < lo
            out.append(f"warning: beam {b.name}: length / sqrt(section area) = {s:.3g} (plausible "
                       f"{lo:g} to {hi:g}): geometry.length {L:g} m against a section of "
                       f"{b.section.area * 1e6:.4g} mm^2; check the units (metres) of "
                       + (f"{_section_key(spec, i)} (too large?)" if short else
                          f"geometry.length (too long?) and {_section_key(spec, i)}"))
            break
    return out


def strain_warning(model, q: np.ndarray, load_factor: float) -> str | None:
    """A warning when some beam's axis (its nodes' r) is stretched or shortened by more than
    ``MAX_FIRST_STRAIN`` at the first converged level (nodal vectors ``q``, (n_nodes, 6, 3))."""
    worst, where = 0.0, None
    for b in model.beams:
        nodes = b.node_offset + np.arange(b.n_nodes)
        d = np.linalg.norm(np.diff(q[nodes, 0], axis=0), axis=1)
        d0 = np.linalg.norm(np.diff(model.q0[nodes, 0], axis=0), axis=1)
        e = d / d0 - 1.0
        k = int(np.argmax(np.abs(e)))
        if abs(e[k]) > abs(worst):
            worst, where = float(e[k]), b.name
    if abs(worst) <= MAX_FIRST_STRAIN:
        return None
    return (f"warning: at the first converged level (load factor {load_factor:g}) beam {where}'s axis "
            f"is {abs(worst) * 100:.0f} % {'longer' if worst > 0 else 'shorter'} (axial strain beyond "
            f"{MAX_FIRST_STRAIN * 100:.0f} %): check the units (SI: N in loads, Pa in materials, "
            "e.g. mu: 103.1e6 not 103.1; m in geometry)")


def point_force_warnings(spec, beams) -> list[str]:
    """One warning per point force on r of a beam with ``locking: mixed``: a point force on r
    deforms the loaded end section in the mode (axial strain ∝ ρ²) that ``mixed`` frees from the
    volumetric term and the quadratic section resists only weakly; the node's displacement is then
    4-5 % larger than without the remedy, where a traction changes nothing (docs/locking.md)."""
    return [f"warning: {ld.path or 'loads'}: a point force on r of beam {beams[ld.beam].name}, which has "
            "locking: mixed; its node's displacement includes the end section's local deformation, which "
            "mixed leaves 4-5 % softer (docs/locking.md): for the beam's response load it with traction_force"
            for ld in spec.loads if ld.kind == "force" and beams[ld.beam].locking == "mixed"]


def fibre_warnings(spec, beams) -> list[str]:
    """One warning per fibre-reinforced beam whose e^(k2 Ē²) overflows below a fibre stretch of
    ``MIN_OVERFLOW_STRETCH`` (Ē = I4 − 1 without dispersion): its fibre stresses there are inf
    (surface_NNNN.vtu stores single precision, which overflows sooner)."""
    out = []
    for i, b in enumerate(beams):
        k2 = getattr(b.material, "k2", None)
        if k2 is None:
            continue
        E = float(np.sqrt(LOG_MAX_DOUBLE / k2))
        stretch = float(np.sqrt(1.0 + E))
        if stretch < MIN_OVERFLOW_STRETCH:
            out.append(f"warning: beams[{i}].material.k2: {k2:g}: the fibre term e^(k2 E^2) of beam {b.name} "
                       f"overflows (inf stress) from a fibre stretch of {stretch:.4g} (E = {E:.3g}); tendon "
                       f"fibres stretch by several per cent; the published sets have k2 = 4.8 to 525 (docs/fibres.md)")
    return out
