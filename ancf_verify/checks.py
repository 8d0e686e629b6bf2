"""Each committed solid reference re-solved today on its coarsest mesh and compared with its CSV
row, and the contact solids' own checks (contact off, tangents against finite differences):
minutes in all, the quick part of ``make verify-solid`` and of tests/solids."""
from __future__ import annotations

import csv
import os
from dataclasses import dataclass

import numpy as np

from ancf_verify.paths import DOCS
from ancf_verify.stack import SolidError


@dataclass
class Check:
    """One check: what, today's value, the committed (or bound) one, the relative difference."""
    name: str
    today: float
    committed: float
    difference: float
    tolerance: float

    @property
    def ok(self) -> bool:
        return bool(self.difference <= self.tolerance)


def _row(rows, what: str, csv_name: str):
    """The first of ``rows`` (an iterator), or a SolidError naming the CSV and the missing row."""
    row = next(rows, None)
    if row is None:
        raise SolidError(f"{csv_name}: no row {what} to re-solve (a CSV of another run?)")
    return row


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.linalg.norm(np.asarray(a) - np.asarray(b)) / np.linalg.norm(b))


def bar(case, docs: str = DOCS) -> Check:
    """A bar of docs/solid_comparison.csv on its coarsest mesh: the end-centroid displacement."""
    from ancf_verify.bars.cases import ancf_section
    from ancf_verify.bars.solid import run_solid
    h = case.h[0]
    path = os.path.join(docs, "solid_comparison.csv")
    with open(path, newline="") as fh:
        want = _row((np.array([float(r[f"u{c}_m"]) for c in "xyz"]) for r in csv.DictReader(fh)
                     if r["case"] == case.key and r["model"] == "solid P2 tet" and r["resolution"] == f"h {h * 1e3:.2f} mm"),
                    f"'{case.key}, solid P2 tet, h {h * 1e3:.2f} mm'", path)
    got = run_solid(case, ancf_section(case), h, repeats=1, max_repeat_time=0.0)["u"]
    return Check(f"bar {case.key}, h {h * 1e3:.2f} mm: |u|", float(np.linalg.norm(got)), float(np.linalg.norm(want)),
                 _rel(got, want), 1e-6)


def fibre_bar(law, docs: str = DOCS) -> Check:
    """The helical-fibre bar (K/μ = 50) of docs/solid_fibres.csv on its coarsest mesh."""
    from ancf_verify.bars.cases import ancf_section
    from ancf_verify.fibres.cases import BULK_RATIOS, H, case_key, make_case
    from ancf_verify.fibres.report import read_csv, runs_of
    from ancf_verify.fibres.solid import run_solid
    case = make_case(law, BULK_RATIOS[0])
    path = os.path.join(docs, "solid_fibres.csv")
    want = _row((r for r in runs_of(read_csv(path)).get(case_key(law.key, BULK_RATIOS[0]), {"solid": []})["solid"]
                 if r["res"] == f"h {H[0] * 1e3:.2f} mm"), f"'{law.key}, solid, h {H[0] * 1e3:.2f} mm'", path)
    got = run_solid(case, ancf_section(case), H[0], 2)
    diff = max(_rel(got["u"], want["u"]), abs(got["levels"][-1]["rot"] / want["rot"] - 1.0),
               0.0 if not got["field_err"] > 1e-10 else np.inf)
    return Check(f"fibre bar {law.key}, h {H[0] * 1e3:.2f} mm: |u|, rotation, fibre field",
                 float(np.linalg.norm(got["u"])), float(np.linalg.norm(want["u"])), diff, 1e-6)


def soft_matrix_bar(docs: str = DOCS) -> Check:
    """The soft-matrix bar of docs/solid_soft_matrix.csv on its coarsest mesh (u, rotation, face mean)."""
    from ancf_verify.bars.cases import ancf_section
    from ancf_verify.fibres.report import read_csv
    from ancf_verify.fibres.solid import run_solid
    from ancf_verify.soft_matrix.cases import H, make_case
    from ancf_verify.soft_matrix.solid import SoftProbe, evaluate
    case = make_case()
    path = os.path.join(docs, "solid_soft_matrix.csv")
    want = _row((r for r in evaluate(read_csv(path))["solid"] if r["res"] == f"h {H[0] * 1e3:.2f} mm"),
                f"'solid, h {H[0] * 1e3:.2f} mm'", path)
    got = run_solid(case, ancf_section(case), H[0], 2, probe=SoftProbe)
    diff = max(_rel(got["u"], want["u"]), abs(got["rot"] / want["rot"] - 1.0),
               abs(got["u_mean"][0] / want["ux_mean"] - 1.0))
    return Check(f"soft-matrix bar, h {H[0] * 1e3:.2f} mm: |u|, rotation, face mean",
                 float(np.linalg.norm(got["u"])), float(np.linalg.norm(want["u"])), diff, 1e-6)


def contact_off(secs, h: float = 4e-3) -> list[Check]:
    """The contact solid with contact off against the bars' solid, body by body (within 2 %)."""
    from ancf_verify.contact.selftest import selftest_single_bodies
    out = selftest_single_bodies(secs, h, 45.0, 20.0, log=lambda *_: None)
    return [Check(f"contact solid, contact off, {b}: u_end against the bar solid", float(np.linalg.norm(out[b]["mine"])),
                  float(np.linalg.norm(out[b]["ref"])), out[b]["rel"], 2e-2) for b in ("soleus", "medial", "lateral")]


def tangents(secs, h: float = 4e-3) -> list[Check]:
    """The sliding contact tangent and the Coulomb tangent against central differences."""
    from ancf_verify.contact.selftest import selftest_fd
    from ancf_verify.friction.study import selftest_fd as friction_fd
    sliding = next(r for r in selftest_fd(secs, h, 45.0, log=lambda *_: None) if r["law"] == "sliding")
    out = [Check("contact tangent (sliding) against finite differences", 0.0, 0.0,
                 min(sliding[e]["full"] for e in (1e-5, 1e-6, 1e-7)), 1e-8)]
    for rec in friction_fd(secs, h, 45.0, log=lambda *_: None):
        out.append(Check(f"Coulomb tangent ({rec['slip']} slip) against finite differences", 0.0, 0.0,
                         min(rec[e]["full"] for e in (1e-5, 1e-6, 1e-7, 1e-8)), 1e-6))
    return out


def every_check(log=print, docs: str = DOCS) -> list[Check]:
    """All of the above against the CSVs in ``docs``, each logged as it completes."""
    from ancf_verify.bars.cases import CASES
    from ancf_verify.contact.tendon import tendon_sections
    from ancf_verify.fibres.cases import LAWS
    from ancf_verify.stack import import_stack
    import_stack()
    out = []
    jobs = [lambda c=c: [bar(c, docs)] for c in CASES] + [lambda: [fibre_bar(LAWS[0], docs)],
                                                        lambda: [soft_matrix_bar(docs)]]
    secs = tendon_sections()
    jobs += [lambda: contact_off(secs), lambda: tangents(secs)]
    for job in jobs:
        for c in job():
            out.append(c)
            log(f"[check] {'ok  ' if c.ok else 'FAIL'} {c.name}: difference {c.difference:.1e} (tolerance {c.tolerance:g})")
    return out
