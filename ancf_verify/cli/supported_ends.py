"""The pressure functions at clamped ends kept or folded (``contact.projection.supported_ends``),
against the 3D solid of docs/solid_friction*.csv (read from the CSVs: nothing solid is solved).

    python scripts/supported_ends_study.py pressure     # normal force near the clamp, μ = 0
    python scripts/supported_ends_study.py friction     # Coulomb μ = 0.3 columns against the solid

``pressure``: per interface, the compressive and tensile normal force Q± = ∫ p± dA within 10 mm
of the clamped roots and beyond, of the frictionless ANCF columns (4/8/16 elements, ψ = 45°, 10
and 100 N) with the ends kept and folded, and of the solid (docs/solid_friction_profiles.csv).
``friction``: the columns of scripts/verify_solid_friction.py (``contact.tangential: {law:
coulomb, friction: 0.3}``) with the ends kept and folded: levels reached, Newton iterations and
the worst errors against the solid reference (soleus relative; gastrocnemii against the soleus
elongation).  Markdown tables on stdout (docs/contact.md, "Supported ends").
"""
from __future__ import annotations

import argparse

from ancf_verify.studies.supported_ends import friction, pressure


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("part", choices=("pressure", "friction"))
    ap.add_argument("--elements", default="4,8,16")
    ap.add_argument("--loads", default="10,100", help="pressure: load levels [N]")
    ap.add_argument("--augmentations", default="default,0.1", help="friction: the Coulomb law's augmentation c")
    args = ap.parse_args(argv)
    elements = [int(e) for e in args.elements.split(",")]
    if args.part == "pressure":
        pressure(elements, [float(F) for F in args.loads.split(",")])
    else:
        friction(elements, [None if s == "default" else float(s) for s in args.augmentations.split(",")])
    return 0
