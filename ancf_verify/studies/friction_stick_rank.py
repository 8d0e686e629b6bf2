"""Why large mu is hard on the tendon (issue 27): exact stick repeats the supports at the roots.

With Coulomb friction by tangential multipliers a sticking pressure function ties the two bodies'
weighted tangential slip to zero (P̄U = 0, contact/friction.py).  Where every function sticks —
at rest, and at μ = 3 over much of the tendon — the interface is tied exactly, and near the
clamped roots, where all three subtendons are held, those ties repeat the supports: the Jacobian
is (numerically) singular, with its near-null vectors in the tangential multipliers of the root
elements.  Such multipliers are not unique, and their functions sit on the stick–slip boundary
(|P̄a| = μẑ), where the semi-smooth Newton iteration flips them from iterate to iterate.

The script prints, for the paper's tendon (ψ = 45°, ``--elements``, the equal-muscles config, at
rest), the smallest singular values of the Jacobian (and relative to the largest) with every function
sticking, and for comparison without friction (sliding) and with the bonded elastic matrix
(k_t = 1e14 Pa/m, the same tie by a penalty), and where the near-null vectors live (interface,
A element of the multipliers carrying them).  ``--tangential-ends merge`` folds the root
functions' tangential vectors into their neighbours' (``contact.tangential.supported_ends``; the
folded vectors are held at zero by rows k_s y = 0).

    OPENBLAS_NUM_THREADS=1 python scripts/friction_stick_rank.py [--elements 4]
"""
from __future__ import annotations

import argparse
import os
import sys

import numpy as np
import yaml

from ancf_verify import paths

ROOT = paths.ROOT
CASES = [("Coulomb mu = 3, every function sticking (at rest)", {"law": "coulomb", "friction": 3.0}),
         ("frictionless sliding", None),
         ("bonded elastic matrix k_t = 1e14 Pa/m", {"law": "elastic", "stiffness": 1e14})]


def problem(tangential, elements: int, ends: str = "keep"):
    from petsc4py import PETSc
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.contact import build_contact
    from ancf_petsc.model.build import build_model
    from ancf_petsc.parallel.partition import make_layout
    from ancf_petsc.petsc.problem import Problem
    with open(os.path.join(ROOT, "configs", "achilles_psi45_equal_muscles.yaml")) as fh:
        raw = yaml.safe_load(fh)
    for b in raw["beams"]:
        b["elements"] = elements
    if tangential and tangential["law"] == "coulomb":
        tangential = tangential | {"supported_ends": ends}
    raw["contact"] = {"mode": "sliding"} | ({"tangential": tangential} if tangential else {})
    spec = parse_config(raw, base_dir=os.path.join(ROOT, "configs"))
    model = build_model(spec)
    contact = build_contact(model, spec.contact, lambda *_: None)
    return Problem(model, make_layout(model, "blocks", 1, 0, contact), PETSc.COMM_WORLD, contact, "aij")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(allow_abbrev=False, description=__doc__.split("\n\n")[0])
    ap.add_argument("--elements", type=int, default=4)
    ap.add_argument("--tangential-ends", choices=("keep", "merge"), default="keep",
                    help="contact.tangential.supported_ends of the Coulomb case (merge: the root "
                         "functions' tangential vectors folded into their neighbours')")
    args = ap.parse_args(argv)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    import petsc4py
    petsc4py.init([sys.argv[0]])
    from petsc4py import PETSc
    for label, tangential in CASES:
        P = problem(tangential, args.elements, args.tangential_ends)
        P.load_factor = 10.0
        P.jacobian(None, P.q0, P.J, P.J)
        J = P.J.convert("dense", PETSc.Mat()).getDenseArray()
        used = np.flatnonzero(np.abs(J).sum(axis=1) > 0)        # drop the padding slots
        U, s, Vt = np.linalg.svd(J[np.ix_(used, used)])
        rel = s / s[0]
        print(f"{label}: {len(used)} unknowns, singular values: largest {s[0]:.2e}, smallest "
              + ", ".join(f"{v:.1e}" for v in s[-4:][::-1])
              + " (relative " + ", ".join(f"{v:.1e}" for v in rel[-4:][::-1]) + ")")
        c = P.contact
        if tangential and tangential["law"] == "coulomb":
            term = c.terms[0]
            tdof = term.tdof[c.mults]                                # (M, 3) serial numbering
            for j in range(1, 4):
                v = np.zeros(J.shape[0])
                v[used] = Vt[-j]
                share = np.linalg.norm(v[tdof.ravel()])
                carry = np.abs(v[tdof]).max(axis=1) > 0.05 * np.abs(v[tdof]).max()
                where = sorted({(int(c.space.interface[m]), int(c.space.element[m])) for m in c.mults[carry]})
                print(f"  near-null vector {j} (singular value {rel[-j]:.1e} of the largest): "
                      f"{share:.3f} of it in the tangential multipliers, carried by the functions of "
                      f"(interface, A element) {where}")
    return 0
