"""``accuracy.section_order: check``: does the scene need a richer section field?

The element ladder (accuracy.py) refines along the beam; the section field's order is the other
rung (3333: linear, 3363: quadratic, ...).  Its indicator: the ladder's start rung — the coarsest
mesh, the scene up to the probe's level — solved again with every beam on the next element of
the section ladder (``physics.elements.richer``, its default locking remedy), and the probe's
relative change between the two.  A change above ``rtol`` says that the section field, not the
mesh along the beam, limits the answer; the run itself keeps the config's element.
"""
from __future__ import annotations

import math
import os
import time

from ..config.parse import parse_config
from ..linalg.database import own_prefix
from ..physics.elements import richer
from .refinement import Discretisation, apply, quantity


def next_order_raw(raw: dict, element: str) -> dict:
    """``raw`` with every beam on ``element`` and its default locking remedy (a bundle: once)."""
    out = apply(raw, Discretisation(element=element))
    for b in out.get("beams", []):
        b.pop("locking", None)
    if "bundle" in out:
        out["bundle"].pop("locking", None)
    return out


def check_section_order(spec, comm, run_model, rung_raw: dict, value: float, level: float, say) -> dict:
    """Solve ``rung_raw`` (the start rung, probe value ``value`` at ``level``) one section order
    up and compare (collective).  Returns the accuracy summary's ``section_order`` entry."""
    acc = spec.accuracy
    names = sorted({b.element for b in spec.beams})
    up = richer(names)
    if up is None:
        say(f"[accuracy] section order: {', '.join(names)} is the top of the section ladder; nothing to compare")
        return {"element": names, "next": None}
    out = os.path.join(spec.output.dir, "accuracy", f"section_{up.name}")
    raw = next_order_raw(dict(rung_raw, output=dict(rung_raw["output"], dir=out)), up.name)
    rung = parse_config(raw, base_dir=spec.base_dir, source=f"accuracy section order {up.name}")
    say(f"[accuracy]   solving the start rung with element {up.name} ...")
    t0 = time.perf_counter()
    with own_prefix(rung.solver, "rung"):          # its PETSc options apart from the ladder's
        res = run_model(rung, comm, lambda *_: None)
    solved = res.status in ("completed", "unstable")
    richer_value = quantity(res.summary, acc.probe, acc.component, level) if comm.rank == 0 and solved else None
    richer_value = comm.tompi4py().bcast(richer_value if solved else math.nan, root=0)
    change = abs(richer_value - value) / abs(richer_value) if richer_value else math.nan
    needs = bool(change > acc.rtol) if math.isfinite(change) else None
    verdict = ("could not be judged: the richer rung " + res.status if needs is None else
               f"the scene needs the richer section field (beams[*].element: {up.name}); this run keeps "
               f"{', '.join(names)}" if needs else "the section field suffices")
    say(f"[accuracy] section order: {', '.join(names)} -> {up.name} on the start rung changes "
        f"{acc.probe} by {change:.2e} (rtol {acc.rtol:g}): {verdict}")
    return {"element": names, "next": up.name, "value": value, "next_value": richer_value,
            "change": change, "needs_next": needs, "status": res.status,
            "seconds": time.perf_counter() - t0}
