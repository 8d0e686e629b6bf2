"""Contact results at a state, gathered over the ranks: per-interface gap and pressure statistics
(every rank's points combined) and the point and multiplier fields on rank 0 (for results.h5 and
the contact VTU files)."""
from __future__ import annotations

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from ..contact import reports
from .problem import Problem


def contact_gaps(problem: Problem, X: PETSc.Vec) -> dict | None:
    """Per-interface gap and pressure statistics at X, each rank over its own points,
    combined (collective)."""
    if problem.contact is None:
        return None
    c = problem.contact

    def sums(xl):      # the exchange's blocks as they are now: ``evaluate`` may have rebuilt it
        return reports.gap_sums(c, c.evaluate(xl, problem.exchange.needed))
    local = problem.exchange.evaluate(X, sums)
    comm = problem.comm.tompi4py()
    out = np.empty_like(local)
    for op, mpi_op in (("max", MPI.MAX), ("sum", MPI.SUM)):
        cols = [k for k, (_, how) in enumerate(reports.report_columns(c)) if how == op]
        part = np.empty((len(local), len(cols)))
        comm.Allreduce(np.ascontiguousarray(local[:, cols]), part, op=mpi_op)
        out[:, cols] = part
    return reports.gap_report(c, out)


def contact_fields(problem: Problem, X: PETSc.Vec) -> dict | None:
    """``Contact.point_fields`` of every rank on rank 0, points sorted by id (``point_*``,
    ``x``, ...) and multipliers sorted by id (``multiplier_*``); collective; None without
    contact and on the other ranks."""
    if problem.contact is None:
        return None
    q0 = problem.model.q0                                       # (n_nodes, 6, 3)
    conn = problem.model.connectivity()

    def q0_of(els):
        return q0[conn[els]].reshape(len(els), problem.model.block.slots, 3)
    def fields(xl):
        out = reports.point_fields(problem.contact, problem.contact.evaluate(xl, problem.exchange.needed), q0_of)
        # the weight each point has in the weighted gaps: 0 for a point whose partner place is
        # past B's curve or beam end (its gap, pressure and slip are then written as 0)
        out["weight"] = problem.contact.weights.values[out["id"]].copy()
        return out
    local = problem.exchange.evaluate(X, fields)
    parts = problem.comm.tompi4py().gather(local, root=0)
    if problem.comm.rank != 0:
        return None
    out = {k: np.concatenate([p[k] for p in parts]) for k in local}
    for key in ("id", "multiplier_id"):
        order = np.argsort(out[key])
        for k in out:
            if k.startswith("multiplier") == key.startswith("multiplier"):
                out[k] = out[k][order]
    return out
