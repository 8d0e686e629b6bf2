"""The contact pressure ACROSS each interface, 3D solid against beams (issue 27, the friction gap).

Coulomb's bound is μ Q⁺ with Q⁺ = ∫ p⁺ dA: a sum of positive parts, so it depends on how the
pressure is distributed across the interface strip, not only on its resultant.  This script
measures that distribution at a load level: per interface and axial window |x − x_c| < Δx/2
(7 mm: each holds a Gauss station of the 4-element beams) of the reference configuration, the pressure averaged over bins of the across coordinate s
(the arc length along the interface curve of the section from the triple point where the three
subtendons meet, at the point's untwisted section position), p̄(s) = Σ w p / Σ w, and the
window's mean compressive and tensile pressures Σ w p± / Σ w (μ times the first is the mean
friction bound per area).  Solid: the slave Gauss points of ancf_verify/friction/model.py (reference area weights w,
interpolated pressure p).  Beams: the contact points of results.h5 (``x0``, ``area``,
``pressure`` = the pressure field Σ_k φ_k λ_k at the point).

    python scripts/solid_friction_across.py                  # solid h 2 mm (μ 0 and 0.3), beams 4/8/16 el.
    python scripts/solid_friction_across.py --no-solid       # the beams only (the CSV's other runs kept)
    python scripts/solid_friction_across.py --h 1.4e-3 --mu 0.3 --elements ""   # one more solid run
    python scripts/solid_friction_across.py --replot         # figure and table from the CSV
    python scripts/solid_friction_across.py --no-solid --mu 0.3 --elements 8 --element 33103 \
        --spaces "default;quadratic across"                  # element 33103 (rows "ANCF 33103 2pt")

Writes docs/solid_friction_across.csv (one row per model, variant, interface, window, s bin) and
docs/figures/solid_friction_across.png (the order-2 beams and the solid) and
docs/figures/solid_friction_across_orders.png (the ``--element`` rows at 8 elements); prints the
table of mean p± per window (docs/interface.md).
"""
from __future__ import annotations

import os
import tempfile

from ancf_verify.cli import Parser, sizes
from ancf_verify.contact.tendon import tendon_sections
from ancf_verify.friction.across import (CSV, across_coordinates, across_md, ancf_points, binned_rows, key,
    plot, plot_orders, read, solid_points, write)
from ancf_verify.friction.rows import SOLID, SPACE, ancf_model
from ancf_verify.stack import import_stack


def main(argv=None) -> int:
    ap = Parser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--load", type=float, default=100.0)
    ap.add_argument("--mu", default="0,0.3", help="friction coefficients (0: frictionless)")
    ap.add_argument("--h", type=sizes, default="2e-3", help="solid mesh sizes [m]")
    ap.add_argument("--elements", default="4,8,16")
    ap.add_argument("--spaces", default="default;quadratic across", help="beam pressure spaces (';')")
    ap.add_argument("--element", default="", help="every beam's element, e.g. 33103 ('': the default, 3363)")
    ap.add_argument("--windows", default="15,35,55", help="window centres x_c [mm]")
    ap.add_argument("--no-solid", action="store_true", help="the beams only (every run not redone is kept)")
    ap.add_argument("--replot", action="store_true")
    args = ap.parse_args(argv)
    if args.replot:
        rows = read()
        plot(rows)
        plot_orders(rows)
        print("\n".join(across_md(rows)))
        return 0
    import_stack()
    psi, F = 45.0, args.load
    centres = [1e-3 * float(x) for x in args.windows.split(",")]
    mus = [float(m) for m in args.mu.split(",")]
    secs = tendon_sections()
    old = read() if os.path.exists(CSV) else []
    solids = {}
    for h in args.h:
        for mu in mus:
            if not args.no_solid:
                print(f"[across] solid h {1e3 * h:.2f} mm, mu {mu:g}, {F:g} N", flush=True)
                solids[(h, mu)] = solid_points(secs, psi, h, mu, F)
    frame = across_coordinates(secs)
    rows = []
    for (h, mu), pts in solids.items():
        rows += binned_rows(pts, frame, centres, {"model": SOLID, "variant": f"mu {mu:g}",
                                                  "resolution": f"h {1e3 * h:.2f} mm", "load_N": F})
    with tempfile.TemporaryDirectory(prefix="across_") as tmp:
        for space in [s.strip() for s in args.spaces.split(";") if s.strip()]:
            for ne in [int(e) for e in args.elements.split(",") if e.strip()]:
                for mu in mus:
                    sp = None if space == "default" else space
                    pts = ancf_points(psi, ne, mu, F, tmp, sp, args.element or None)
                    print(f"[across] {ancf_model(args.element)} {ne} el., mu {mu:g}, pressure {space}: "
                          + ("done" if pts else "did not reach the level"), flush=True)
                    if pts:
                        rows += binned_rows(pts, frame, centres, {
                            "model": ancf_model(args.element),
                            "variant": f"mu {mu:g}" + ("" if sp is None else f"{SPACE}{sp}"),
                            "resolution": f"{ne} el.", "load_N": F})
    new = {key(r) for r in rows}
    rows = [r for r in old if key(r) not in new] + rows      # the runs not redone are kept
    write(rows)
    plot(rows)
    plot_orders(rows)
    print("\n".join(across_md(rows)))
    return 0
