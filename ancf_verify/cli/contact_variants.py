"""What limits the ANCF sliding columns against the 3D solid with contact (issue 24, point 3):
the soleus elongation of contact-discretisation variants against the solid reference of
docs/solid_contact.csv (read from the CSV: no dolfinx, nothing solid is solved).

    python scripts/solid_contact_variants.py                     # every variant, 4/8/16 el, ψ 0/15/45
    python scripts/solid_contact_variants.py --variants "default;free" --elements 4

Each ANCF column is the one of scripts/verify_solid_contact.py (``tendon_config``: clamped roots,
end traction on the soleus, 2 axial Gauss points), run in this process with the variant's
``contact:`` keys.  Variants: the pressure space (``projection``), the density of the contact
points (``axial_points``, ``curve_points``), the soleus alone (``free``: the beam's own error),
and a coarser mesh's pressure space on this mesh's displacements (``build_space(group=G)``: the
functions of the 4- or 8-element space on 8 or 16 elements, to tell the pressure space from the
displacements).  Prints, per variant, ψ and element count, the worst signed error over the
solid's loads and the error at 10 N, as a markdown table (docs/solid_contact.md, "What limits
4 elements").
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile

from ancf_verify.contact.rows import read_csv
from ancf_verify.paths import ROOT
from ancf_verify.studies.contact_variants import VARIANTS, reference, run_column


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--variants", default=";".join(VARIANTS), help="names separated by ;")
    ap.add_argument("--elements", default="4,8,16")
    ap.add_argument("--psi", default="0,15,45")
    args = ap.parse_args(argv)
    names = [v.strip() for v in args.variants.split(";") if v.strip()]
    unknown = [v for v in names if v not in VARIANTS]
    if unknown:
        print(f"solid_contact_variants: unknown variants {unknown}; known: {', '.join(VARIANTS)}",
              file=sys.stderr)
        return 2
    elements = [int(e) for e in args.elements.split(",")]
    psis = [float(p) for p in args.psi.split(",")]
    rows = read_csv(os.path.join(ROOT, "docs", "solid_contact.csv"))
    print("| variant | ψ | " + " | ".join(f"{e} el. worst (10 N)" for e in elements) + " |")
    print("|---|---:|" + "---:|" * len(elements))
    with tempfile.TemporaryDirectory(prefix="solid_variants_") as tmp:
        for name in names:
            ref = reference(rows, "free" if VARIANTS[name][2] is None else "sliding")
            for psi in psis:
                cells = []
                for e in elements:
                    u = run_column(psi, e, name, tmp)
                    errs = {F: (u[F] - ref[(psi, F)]) / ref[(psi, F)] for F in u or {} if (psi, F) in ref}
                    worst = max(errs.values(), key=abs) if errs else None
                    cells.append("—" if worst is None else
                                 f"{100 * worst:+.3f} % ({100 * errs.get(10.0, float('nan')):+.3f} %)")
                print(f"| {name} | {psi:g}° | " + " | ".join(cells) + " |", flush=True)
    return 0
