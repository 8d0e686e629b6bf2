"""solving/continuity.py: on a level's final failure the residual is scanned along Newton's last
steps for a jump (a discontinuity of the discrete model, not a limit point), found to rounding
and named by where it acts; a continuous residual gives none.  On a real contact problem (the
paper's outlines, 2 elements, sliding) with a jump of 1 N injected into one beam node's row
where the state crosses a plane, on 1 rank and on 2 (the scan is collective, the place is said
by the rank that holds it); and the failure message carries it.  The jump's cause from the
contact's projections (a closest point on another B element, at a common node or not, or a
point's weight): on the real projections of that problem with one point moved to the next
element, the same words on every rank, and on made-up projections each case's words."""
import os
import subprocess
import sys

import pytest

from helpers import MPI_ENV, ROOT

SCRIPT = r"""
import numpy as np
from contact.test_contact import achilles
from helpers import build_problem
from ancf_petsc.solving.continuity import IterateTrail, residual_jump, jump_detail

def trail_and_plane(P):
    # four iterates q0 + k (0.2 um ... ) along a smooth path; the plane halfway between the 2nd and 3rd
    X = P.q0.copy()
    lo, hi = X.getOwnershipRange()
    idx = np.arange(lo, hi)
    trail, states = IterateTrail(), []
    for k in range(4):
        Y = X.copy()
        Y.setArray(X.getArray() + 2e-7 * k * np.sin(0.37 * idx + k))
        trail.record(k, Y, float(k))
        states.append(Y)
    w = states[2].copy()
    w.axpy(-1.0, states[1])
    mid = states[1].copy()
    mid.axpy(0.5, w)
    return trail, w, w.dot(mid)

P, PETSc = build_problem(achilles(contact={"mode": "sliding"}))
beam = P.model.beams[1]
node = beam.node_offset + 3
D = P.X.getBlockSize()
dof = int(P.layout.perm[node]) * D + 1
trail, w, level = trail_and_plane(P)
assert residual_jump(P, trail, 0.5) is None             # the residual itself is continuous here
plain = P.residual

def jumping(snes, X, F):
    plain(snes, X, F)
    if X.dot(w) > level:                                 # collective; the owner adds 1 N
        lo, hi = F.getOwnershipRange()
        if lo <= dof < hi:
            F.setValue(dof, 1.0, addv=PETSc.InsertMode.ADD_VALUES)
        F.assemble()

P.residual = jumping
jump = residual_jump(P, trail, 0.5)
assert jump is not None and abs(jump.size - 1.0) < 1e-6, jump
assert jump.where == f"beam {beam.name}, node 3", jump.where
assert "jumps by 1 N" in jump_detail(jump) and jump_detail(None) == ""
assert jump.cause == "" and "please report it" in jump_detail(jump)   # not the contact's doing
assert jump.kind == "residual_jump", jump.kind

# the cause on real projections: a point's closest point moved to the next element, at their
# common node; the rank that holds it says, every rank gets the same words
import dataclasses
from mpi4py import MPI
from ancf_petsc.solving.continuity import contact_cause
P.residual = plain
c = P.contact
c.allow_update = False
a = c.evaluate(P.exchange.local_state(P.q0).copy(), P.exchange.needed).pr
good = a.valid & np.all(np.isfinite(a.n), axis=1)
pid = P.comm.tompi4py().allreduce(int(a.idx[good].min()) if good.any() else 10**9, op=MPI.MIN)
xa, eb, xb, nb = a.xiB.copy(), a.eB.copy(), a.xiB.copy(), a.n.copy()
mine = np.flatnonzero(a.idx == pid)
for k in mine:
    xa[k], eb[k], xb[k] = 1.0, a.eB[k] + 1, -1.0
    nb[k] = [a.n[k, 0], -a.n[k, 2], a.n[k, 1]]             # turned by 90 deg about x
kind, text = contact_cause(c, dataclasses.replace(a, xiB=xa), dataclasses.replace(a, eB=eb, xiB=xb, n=nb),
                           P.comm.tompi4py())
assert P.comm.tompi4py().allgather((kind, text)) == [(kind, text)] * P.comm.size and kind == "c0_kink"
itf = c.interfaces[int(c.points.itf[pid])]
assert text.startswith(f"; there contact point {pid} (on {itf.a.name}) of interface {itf.name} has its closest point")
assert "only C0 across its element boundaries" in text and "turns by 90 deg" in text, text
if P.comm.rank == 0:
    print("ok", P.comm.size)
"""


def _run(ranks: int) -> subprocess.CompletedProcess:
    cmd = [sys.executable, "-c", SCRIPT]
    if ranks > 1:
        cmd = ["mpirun", "--oversubscribe", "-n", str(ranks)] + cmd
    env = dict(os.environ, **MPI_ENV, PYTHONPATH=os.pathsep.join([ROOT, os.path.join(ROOT, "tests")]))
    return subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)


def test_a_jump_is_found_to_rounding_and_named():
    p = _run(1)
    assert p.returncode == 0 and "ok 1" in p.stdout, p.stdout + p.stderr


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [2, 3])
def test_the_scan_on_ranks_finds_the_same_jump(ranks):
    p = _run(ranks)
    assert p.returncode == 0 and f"ok {ranks}" in p.stdout, p.stdout + p.stderr


def test_the_trail_keeps_the_last_iterates_in_order():
    """``IterateTrail``: the last TRAIL iterates of a solve, oldest first, with the rise of |F|
    along each step; a new solve (iteration 0) starts it again."""
    from petsc4py import PETSc
    from ancf_petsc.solving.continuity import TRAIL, IterateTrail
    trail = IterateTrail()
    v = PETSc.Vec().createSeq(2)
    for its in range(TRAIL + 3):
        v.set(float(its))
        trail.record(its, v, 10.0 * its)
    steps = trail.steps()
    assert len(steps) == TRAIL - 1
    assert [a.getArray()[0] for a, _, _ in steps] == [float(k) for k in range(3, TRAIL + 2)]
    assert all(rise == 10.0 for _, _, rise in steps)
    v.set(-1.0)
    trail.record(0, v, 5.0)
    assert trail.steps() == []
    trail.destroy()
    v.destroy()


def _projection(eB, xiB, normals, weight):
    from types import SimpleNamespace
    import numpy as np
    n = np.array(normals, float)
    return SimpleNamespace(idx=np.array([7, 8]), eB=np.array(eB), xiB=np.array(xiB, float),
                           n=n / np.linalg.norm(n, axis=1)[:, None], weight=np.array(weight, float),
                           valid=np.array([True, True]))


def _contact():
    from types import SimpleNamespace
    import numpy as np
    beam = lambda name, offset=0: SimpleNamespace(name=name, element_offset=offset)   # noqa: E731
    itf = SimpleNamespace(name="mg_sol", a=beam("medial_gastrocnemius"), b=beam("soleus", 4))
    return SimpleNamespace(interfaces=[itf], points=SimpleNamespace(itf=np.zeros(9, dtype=int)))


def test_the_cause_names_a_closest_point_that_changes_element():
    """Two states a rounding apart whose projections put point 8's closest point on the soleus'
    elements 1 and 2 (global 5 and 6) at their common node, the normals 5 deg apart: the cause
    names the point, the interface, both elements and the turn, and the failure message no longer
    asks for a report; a weight that changes is named when no point changes element."""
    import numpy as np
    from mpi4py import MPI
    from ancf_petsc.solving.continuity import Jump, contact_cause, jump_detail
    t = np.radians(5.0)
    a = _projection([5, 5], [0.2, 1.0], [[0, 0, 1], [0, 0, 1]], [1.0, 0.5])
    b = _projection([5, 6], [0.2, -1.0], [[0, 0, 1], [0, np.sin(t), np.cos(t)]], [1.0, 0.5])
    kind, text = contact_cause(_contact(), a, b, MPI.COMM_SELF)
    assert kind == "c0_kink"
    assert ("contact point 8 (on medial_gastrocnemius) of interface mg_sol has its closest point on "
            "soleus's element 1 at xi = +1.0000 on one side and on element 2 at xi = -1.0000") in text
    assert "only C0 across its element boundaries" in text and "turns by 5 deg" in text
    detail = jump_detail(Jump(size=0.12, scale=0.14, where="beam soleus, node 4", cause=text))
    assert "node 4; there contact point 8" in detail and "please report" not in detail
    b = _projection([5, 6], [0.2, -0.4], [[0, 0, 1], [0, np.sin(t), np.cos(t)]], [1.0, 0.5])
    kind, text = contact_cause(_contact(), a, b, MPI.COMM_SELF)      # element 2 but not near the node
    assert kind == "two_closest_points" and text.endswith("element 2 at xi = -0.4000 on the other: two places of B about as near to "
                         "the point, their normals 5 deg apart")
    b = _projection([5, 5], [0.2, 1.0], [[0, 0, 1], [0, 0, 1]], [1.0, 0.25])
    kind, text = contact_cause(_contact(), a, b, MPI.COMM_SELF)
    assert kind == "fade_weight_jump" and text == "; there the weight of contact point 8 (on medial_gastrocnemius) of interface mg_sol changes from 0.5 to 0.25"
    assert contact_cause(_contact(), a, a, MPI.COMM_SELF) == ("residual_jump", "")
