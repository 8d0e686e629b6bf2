"""A restart's load curves (``load_curve_k`` of the fingerprint, io/restart.py): what differs, in
words, and which config entries follow the curve; a load history that only grows past the
restart point is the run's (the levels up to it read no later frame), also where loads that
shared one curve up to it follow different ones after it (two columns equal in every frame
solved: the model groups loads by curve)."""
from __future__ import annotations

import numpy as np


def grown_histories(stored: dict, now: dict, lam: float) -> dict:
    """``stored`` with each load curve that ``now`` only extends after load factor ``lam`` taken
    as ``now``'s (frames appended to a history; its points up to the first at or past ``lam``
    and its loads at multiplier 1 the same): m(λ) on [0, lam] is unchanged."""
    n_dofs = np.asarray(now.get("reference_nodal_vectors", ())).size
    out = dict(stored)
    for key, a in stored.items():
        if key.startswith("load_curve_") and key in now and n_dofs and _extends(a, now[key], lam, n_dofs):
            out[key] = now[key]
    if n_dofs and _same_groups(_groups_up_to(out, lam, n_dofs), _groups_up_to(now, lam, n_dofs)):
        out = {k: v for k, v in out.items() if not k.startswith("load_curve_")}
        out.update((k, v) for k, v in now.items() if k.startswith("load_curve_"))
    return out


def _extends(a: np.ndarray, b: np.ndarray, lam: float, n_dofs: int) -> bool:
    """Whether curve item ``b`` (points (λ, m), then forces and moves, ``n_dofs`` each) equals
    ``a`` on [0, lam]: the same loads, and the same points through the first at or past lam."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    na, nb = a.size - 2 * n_dofs, b.size - 2 * n_dofs
    if min(na, nb) < 2 or na % 2 or nb % 2 or not _close(a[na:], b[nb:]):
        return False
    pa, pb = a[:na].reshape(-1, 2), b[:nb].reshape(-1, 2)
    n = _points_through(pa, lam)
    return n is not None and n <= len(pb) and _close(pa[:n], pb[:n])


def _points_through(points: np.ndarray, lam: float) -> int | None:
    """How many of a curve's (λ, m) ``points`` define it on [0, lam] (through the first at or
    past lam); None when lam lies past its end (m held there)."""
    lam_past = lam - 1e-12 * max(1.0, abs(lam))
    past = np.nonzero(points[:, 0] >= lam_past)[0]
    if not past.size:
        return None
    return max(int(past[0]) + 1, int(np.count_nonzero(points[:, 0] <= lam + (lam - lam_past))))


def _groups_up_to(items: dict, lam: float, n_dofs: int) -> list | None:
    """The load curves of a fingerprint on [0, lam], those equal there merged: [points, forces,
    moves] each (the loads they give there); None if one is not a curve item."""
    groups: list = []
    for key in sorted(k for k in items if k.startswith("load_curve_")):
        a = np.asarray(items[key], dtype=float)
        na = a.size - 2 * n_dofs
        n = None if na < 2 or na % 2 else _points_through(a[:na].reshape(-1, 2), lam)
        if n is None:
            return None
        points, forces, moves = a[:na].reshape(-1, 2)[:n], a[na:na + n_dofs], a[na + n_dofs:]
        same = [g for g in groups if _close(g[0], points)]
        if same:
            same[0][1], same[0][2] = same[0][1] + forces, same[0][2] + moves
        else:
            groups.append([points, forces, moves])
    return groups


def _same_groups(a: list | None, b: list | None) -> bool:
    """Whether two fingerprints' merged curves (``_groups_up_to``) give the same loads."""
    if a is None or b is None or len(a) != len(b):
        return False
    return all(any(all(_close(x, y) for x, y in zip(ga, gb)) for gb in b) for ga in a)


def same_curve(a: np.ndarray, b: np.ndarray) -> bool:
    """Two ``load_curve_k`` items equal to the fingerprint's tolerance."""
    return _close(np.asarray(a, dtype=float), np.asarray(b, dtype=float))


def _close(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal to the fingerprint's tolerance (io/restart.first_difference)."""
    return a.shape == b.shape and bool(np.allclose(
        a, b, rtol=1e-12, atol=1e-300 + 1e-12 * float(np.max(np.abs(a), initial=0.0))))


def curve_difference(a: np.ndarray, b: np.ndarray, n_dofs: int) -> str:
    """What differs between two ``load_curve_k`` items (the curve's (λ, m) points, then the
    group's forces and displacements at multiplier 1, ``n_dofs`` each), in words: a history's
    frame k is the point at load factor k."""
    na, nb = (a.size - 2 * n_dofs) // 2, (b.size - 2 * n_dofs) // 2
    m = min(na, nb)
    if not _close(a[:2 * m], b[:2 * m]):          # a point both have: a frame changed
        k = int(np.argmax(np.abs(a[:2 * m] - b[:2 * m])))
        j = k // 2
        if k % 2:
            lam = a[2 * j]
            return (f"its multiplier at load factor {lam:g} (a history: frame {lam:g}) "
                    f"{a[k]:.9g} → {b[k]:.9g}")
        return f"the load factor of its point {j}: {a[k]:.9g} → {b[k]:.9g}"
    if na != nb and _close(a[2 * na:], b[2 * nb:]):
        return (f"its curve has {na} → {nb} points (a load history: frames and the rest state; "
                "frames may be added or changed only after the restart's level)")
    return "its loads or prescribed displacements at multiplier 1 differ"


def curve_owner(model, key: str) -> str:
    """``load_curve_k`` of the fingerprint as the config entries that follow that curve, with the
    history columns they read."""
    k = int(key.rpartition("_")[2])
    groups = [g for g in model.loading if g.curve is not None]
    if k >= len(groups):
        return key
    points = np.asarray(groups[k].curve.points, dtype=float)
    owners = []
    for item, name in [*((x, "loads") for x in model.spec.loads),
                       *((x, "boundary_conditions") for x in model.spec.boundary_conditions)]:
        if item.curve is None or np.shape(item.curve) != points.shape or not np.allclose(item.curve, points):
            continue
        raw = model.spec.raw.get(name, []) if isinstance(model.spec.raw, dict) else []
        index = int(item.path.rpartition("[")[2].rstrip("]")) if item.path.endswith("]") else -1
        column = raw[index].get("column") if 0 <= index < len(raw) and isinstance(raw[index], dict) else None
        owners.append(item.path + (f" (column {column!r})" if column else ""))
    return "the load curve of " + ", ".join(owners) if owners else key
