"""Continue a run from the last converged level in its results.h5 (``ancf-solve --restart DIR``).

Every converged level stores what the load stepping needs to go on exactly as an uninterrupted
run would (results.py): the nodal vectors, the contact multipliers, the projection state of every
contact point and the status of every multiplier, the last accepted increment of the state and
of the load, and the next load increment.  All of it is in model order, so a restart may use
another number of ranks.

The model must be the one that wrote the file.  Not its YAML text (``units: SI`` left out,
``1.031e+08`` for ``103.1e6``, ``node: -1`` for ``last``, another path to the same file are the
same model; a section file whose pixel scale changed between the kill and the restart is not):
the resolved model is compared, item by item (``fingerprint``: reference nodal vectors, every
beam's connectivity, nodes, section rule and material, the supported DOFs, the loads and the
contact spec), and the first difference is named.  The converged levels must be the first
levels of the config's steps; a load curve may differ after the restart's level
(restart_curves.py: frames appended to a history).
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass

import numpy as np
import yaml

from ..config.contact import bounded
from ..config.specs import LOCKING
from ..contact.interfaces import ContactSetupError, find_interfaces, supported_ends
from ..contact.tangential import TANGENTIAL_LAWS
from ..errors import InputError
from .restart_curves import curve_difference, curve_owner, grown_histories, same_curve
from .restart_places import difference_text

#: config keys that define the model (a restart must not change them; steps, solver, petsc,
#: output and partition may change)
MODEL_KEYS = ("units", "geometry", "beams", "boundary_conditions", "loads", "contact", "bundle")


@dataclass
class RestartPoint:
    """The last converged level of a run, read from its results.h5 (model order)."""
    step: int                     # its number (1-based)
    load_factor: float
    blocks: np.ndarray            # (n_blocks, D): nodal vectors, then multiplier blocks (D DOFs per node)
    increment_blocks: np.ndarray  # (n_blocks, D): the last accepted increment of the state
    increment: float              # the next load increment
    last_increment: float         # the last accepted one
    accepted_negative: int
    projection: np.ndarray | None  # (points, 3) e_B, ξ_B, t_B
    status: np.ndarray | None      # (multipliers,) active
    summary: dict                 # summary.json with the steps up to ``step``
    fingerprint: dict | None = None   # the stored model's (None: written before fingerprints)
    stored_config: dict | None = None  # its config (runs without a fingerprint)
    levels: tuple = ()            # the converged load factors, in order
    contact_fields: dict | None = None   # the level's contact fields (a contact term's state)
    #: the history of the tangent the run factored last: the level before the last one that took
    #: Newton iterations (None: from rest; ``_factoring_level``)
    previous_contact_fields: dict | None = None
    pointwise_from: float | None = None  # the run's switch to pointwise fade forces (fade_switch.py)
    window_whole_from: float | None = None  # its contact search windows widened (window_widening.py)
    settled_increments: int = 0   # increments whose active set settled in a row (solving/newton.py)


def fingerprint(model) -> dict[str, np.ndarray]:
    """What defines the discrete model, as named arrays (a restart compares them)."""
    spec = model.spec
    out = {"reference_nodal_vectors": np.asarray(model.q0, dtype=float),
           "supported_dofs": np.asarray(model.fixed_dofs, dtype=float),
           "loads": np.asarray(model.f_ext, dtype=float),
           "length": np.array([spec.length]), "twist_deg": np.array([spec.twist_deg])}
    if np.any(model.prescribed):                  # displacement control (absent: as before)
        out["prescribed_displacements"] = np.asarray(model.prescribed, dtype=float)
    for k, g in enumerate(g for g in model.loading if g.curve is not None):
        out[f"load_curve_{k}"] = np.concatenate([np.ravel(g.curve.points), g.forces, g.moves])
    for b in model.beams:
        m = b.material
        params = [float(v) for k, v in sorted(vars(m).items()) if isinstance(v, (int, float))]
        out.update({f"beams/{b.name}/elements": np.array([float(b.n_elements)]),
                    f"beams/{b.name}/element": _word(b.element),
                    f"beams/{b.name}/axial_points_locking": np.array(
                        [float(b.axial_points), LOCKING.index(b.locking)]),
                    f"beams/{b.name}/material": np.array(params),
                    f"beams/{b.name}/x_nodes": np.asarray(b.x_nodes),
                    f"beams/{b.name}/section_points": np.asarray(b.yz, dtype=float),
                    f"beams/{b.name}/section_weights": np.asarray(b.wq, dtype=float),
                    f"beams/{b.name}/connectivity": np.asarray(b.connectivity, dtype=float)})
        if getattr(b, "fibres", None) is not None:          # fibre directions per Gauss point
            out[f"beams/{b.name}/fibres"] = np.asarray(b.fibres, dtype=float)
    c = spec.contact
    if c is not None:
        words = {"mode": c.mode, "projection": list(c.projection), "axial_points": c.axial_points,
                 "curve_points": c.curve_points, "per_element": c.per_element,
                 "interfaces": _resolved_interfaces(model, c),
                 "fade_forces": "variational" if c.fade == "newton" and c.fade_forces != "pointwise" else "pointwise",
                 "scaling": c.scaling}
        folded = _folded_ends(model, c)
        if folded:                        # pressure functions folded at clamped ends (else: as before)
            words["supported_ends"] = folded
        if c.tangential is not None and TANGENTIAL_LAWS[c.tangential.law] is not None:   # frictionless: as before
            words["tangential"] = vars(c.tangential)
        out["contact"] = _word(json.dumps(words, sort_keys=True))
    return out


def _word(text: str) -> np.ndarray:
    """A string as a fingerprint array (its UTF-8 bytes as floats)."""
    return np.frombuffer(text.encode(), dtype=np.uint8).astype(float)


def _text(a: np.ndarray) -> str:
    return bytes(np.asarray(a).astype(np.uint8)).decode()


def _current(fp: dict) -> dict:
    """A fingerprint in today's items: files written before the element name was a string store
    ``element_axial_points_locking`` = [element number, axial points, locking]."""
    out = dict(fp)
    for key in [k for k in fp if k.endswith("/element_axial_points_locking")]:
        beam = key.rpartition("/")[0]
        e, axial, locking = np.asarray(out.pop(key), dtype=float)
        out[f"{beam}/element"] = _word(f"{e:g}")
        out[f"{beam}/axial_points_locking"] = np.array([axial, locking])
    return out


def _folded_ends(model, contact) -> list[str]:
    """The interface ends whose end pressure function is folded into its neighbour
    ("name first|last"; contact/interfaces.supported_ends): it changes the multiplier space."""
    try:
        interfaces = find_interfaces(model, contact)
    except ContactSetupError:           # reported by the contact setup itself
        return []
    ends = supported_ends(model, interfaces, contact.supported_ends)
    return [f"{i.sides} {('first', 'last')[j]}" for i, row in zip(interfaces, ends) for j in range(2) if row[j]]


def _resolved_interfaces(model, contact) -> list[str]:
    """The interfaces contact will use ("curve (A|B)", A the beam carrying the points, sorted):
    ``auto`` and the same pairs written out are one model."""
    try:
        return sorted(i.sides for i in find_interfaces(model, contact))
    except ContactSetupError:           # reported by the contact setup itself
        return [repr(i) for i in (contact.interfaces or [])]


def model_difference(stored: dict, now: dict) -> str | None:
    """The first item that differs between two fingerprints, with what changed (None: same);
    a beam's items first (in this model's order), then the model-wide ones."""
    found = first_difference(stored, now)
    return None if found is None else f"{found[0]} ({found[1]})"


def first_difference(stored: dict, now: dict) -> tuple[str, str] | None:
    """``model_difference`` as (fingerprint key, what changed), None when the same."""
    fields = ("elements", "element", "axial_points_locking", "material", "fibres", "x_nodes",
              "section_points", "section_weights", "connectivity")
    stored, now = _current(stored), _current(now)

    beams: dict[str, int] = {}
    for key in now:                               # beams in the order the model has them
        beams.setdefault(key.rpartition("/")[0], len(beams))

    def order(key: str):
        beam, _, field = key.rpartition("/")
        return (0, beams[beam], fields.index(field) if field in fields else len(fields)) if beam else (1, 0, 0)
    keys = sorted(now, key=order)
    for key in keys + [k for k in stored if k not in now]:
        if key not in stored or key not in now:
            return key, "added" if key in now else "removed"
        a, b = np.asarray(stored[key]), np.asarray(now[key])
        if key == "contact":
            if not np.array_equal(a, b) and _words_difference(a, b):
                return key, _words_difference(a, b)
            continue
        if key.endswith("/element") and not np.array_equal(a, b):
            return key, f"{_text(a)} → {_text(b)}"
        if key.startswith("load_curve_") and "reference_nodal_vectors" in now and not same_curve(a, b):
            return key, curve_difference(a, b, np.asarray(now["reference_nodal_vectors"]).size)
        if a.shape != b.shape:
            return key, f"shape {a.shape} → {b.shape}"
        if not np.allclose(a, b, rtol=1e-12, atol=1e-300 + 1e-12 * float(np.max(np.abs(a), initial=0.0))):
            if key.endswith("section_weights"):
                return key, f"section area {a.sum():.6g} → {b.sum():.6g} of the rule's units"
            k = int(np.argmax(np.abs(a - b)))
            if a.size == 1:
                return key, f"{a.ravel()[0]:.9g} → {b.ravel()[0]:.9g}"
            return key, f"largest change at entry {k}: {a.ravel()[k]:.9g} → {b.ravel()[k]:.9g}"
    return None


#: contact words stored since 2026-12-07 (the fade forces' form: another equilibrium where points
#: fade; the multipliers' unit: another meaning of the stored multipliers): a file without them
#: is not compared on them
LATER_WORDS = ("fade_forces", "scaling")


def _words_difference(a: np.ndarray, b: np.ndarray) -> str:
    """The contact settings that differ between two fingerprints' ``contact`` words."""
    sa, sb = (json.loads(_text(x)) for x in (a, b))
    keys = sorted(k for k in set(sa) | set(sb) if sa.get(k) != sb.get(k)
                  and not (k in LATER_WORDS and (k not in sa or k not in sb)))
    return ", ".join(f"{k}: {sa.get(k, 'absent')} → {sb.get(k, 'absent')}" for k in keys)


def check_same_run(point: RestartPoint, model, steps: list, directory: str = "") -> None:
    """InputError naming the first difference between the restart's run and this model and
    steps (fingerprint of the resolved model; the converged levels must start the steps)."""
    if point.fingerprint is not None:
        stored = point.fingerprint
        if point.pointwise_from is not None:      # went on pointwise: fade_switch.resume checks the form
            words = json.loads(_text(stored["contact"]))
            words.pop("fade_forces", None)
            stored = dict(stored, contact=_word(json.dumps(words, sort_keys=True)))
        now = fingerprint(model)
        found = first_difference(grown_histories(stored, now, point.load_factor), now)
        differs = None if found is None else f"{difference_text(model, found, stored, now)} differs"
        if found is not None and found[0].startswith("load_curve_"):
            differs = f"{curve_owner(model, found[0])}: {found[1]}"
    else:                                         # written before fingerprints: the YAML keys
        raw = model.spec.raw
        differs = _first_difference({k: point.stored_config.get(k) for k in MODEL_KEYS},
                                    {k: raw.get(k) for k in MODEL_KEYS})
        differs = differs and f"{differs} differs"
    if differs:
        raise InputError("--restart", f"{directory} was written by another model: {differs}; "
                                      + (_friction_default_hint(point, model)
                                         or "restart with the config (and data files) that made it"))
    entries = point.summary.get("steps") or []
    for k, lam in enumerate(point.levels):       # a level passed over: the one it was asked for
        lam = ((entries[k].get("passed_over") or {}) if k < len(entries) else {}).get("level", lam)
        if k >= len(steps) or abs(steps[k] - lam) > 1e-12 * max(1.0, abs(lam)):
            now = f"{steps[k]:g}" if k < len(steps) else "none (the config has fewer levels)"
            raise InputError("--restart", f"the config's steps differ from the run's converged "
                                          f"levels at step {k + 1}: {lam:g} was solved, the config asks "
                                          f"for {now}; restart with the steps that made them, or "
                                          "run afresh into another directory")
    _check_clock(entries[:len(point.levels)], model.spec.history, directory)


def _check_clock(entries: list, history, directory: str) -> None:
    """The times [s] of the frames solved must be the history's: a clock column changed between
    the kill and the restart (ms for s) was taken, and the run's outputs went 0.04, 0.14, 240,
    340 s."""
    for k, e in enumerate(entries if history is not None else []):
        now = history.time_of(e["load_factor"])
        if "time" in e and not np.isclose(e["time"], now, rtol=1e-12, atol=0.0):
            raise InputError("--restart", f"{directory} was written with another clock: frame "
                                          f"{e.get('frame', k + 1)} was at {e['time']:g} s, the column "
                                          f"{history.time_column!r} of {history.source} gives {now:g} s; "
                                          "restart with the table that made it, or run afresh into "
                                          "another directory")


def _friction_default_hint(point: RestartPoint, model) -> str | None:
    """What to give when the run's pressure along the beam was friction's default before
    2026-12-07 (quadratic) and the config, giving none, now takes the linear one."""
    spec = model.spec.contact
    given = ((model.spec.raw.get("contact") or {}).get("projection") or {})
    if point.fingerprint is None or spec is None or "axial" in given or not bounded(spec):
        return None
    stored = json.loads(_text(point.fingerprint["contact"])).get("projection")
    if not stored or stored[0] <= spec.projection[0]:
        return None
    return (f"friction's pressure along the beam is linear by default since 2026-12-07 "
            "(docs/interface.md, \"Friction's pressure along the beam\"): give contact.projection: "
            f"{{axial: {stored[0]}}} in the config to continue this run")


def _first_difference(old, new, path: str = "") -> str | None:
    """Key path of the first difference between two config trees (None if equal)."""
    if isinstance(old, dict) and isinstance(new, dict):
        for key in list(old) + [k for k in new if k not in old]:
            sub = f"{path}.{key}" if path else str(key)
            if key not in old or key not in new:
                return sub
            found = _first_difference(old[key], new[key], sub)
            if found:
                return found
        return None
    if isinstance(old, list) and isinstance(new, list):
        if len(old) != len(new):
            return f"{path} (length {len(old)} → {len(new)})"
        for i, (a, b) in enumerate(zip(old, new)):
            found = _first_difference(a, b, f"{path}[{i}]")
            if found:
                return found
        return None
    return None if old == new else path


def _datasets(group) -> dict:
    """Every dataset under an h5py group, by its path inside it."""
    out = {}
    group.visititems(lambda name, obj: out.__setitem__(name, obj[()]) if hasattr(obj, "shape") else None)
    return out


def _contact_fields(group) -> dict | None:
    """A level's contact fields (its contact group's datasets), None without contact."""
    return {key: v[()] for key, v in group["contact"].items()} if "contact" in group else None


def _factoring_level(entries: list, k: int) -> int:
    """The last of the levels 1 … k whose solve took Newton iterations, whose factor the run's
    tangent predictor holds: a level reached in none (a frame repeating the loads of the one
    before) factors nothing (0: none did; the first level's stability count factored the rest
    state, SNESSolver.factor_at).  Priming with the history of the level before k instead made a
    friction history restarted at such a frame go on along another path."""
    return next((i for i in range(k, 0, -1) if entries[i - 1].get("iterations", 1) > 0), 0)


def read_restart(directory: str) -> RestartPoint:
    """The last converged level of the run in ``directory`` (``check_same_run`` compares it
    with the continuing run's model).  InputError with one line when the directory has no
    usable results."""
    import h5py

    from .reader import append_levels
    path = os.path.join(directory, "results.h5")
    if not os.path.isfile(path):
        raise InputError("--restart", f"{path}: no such file (restart from a run's output directory)")
    summary_path = os.path.join(directory, "summary.json")
    try:
        with open(summary_path) as fh:
            summary = json.load(fh)
    except (OSError, ValueError):
        summary = {"steps": []}
    try:
        with h5py.File(path, "r") as h5:
            stored = yaml.safe_load(h5["model"].attrs["config_yaml"])
            steps = h5["steps"]
            # summary.json may lag results.h5 (SUMMARY_SHARE, a kill between them): the levels after it
            # come from results.h5 (their summary_entry); a level without one (an older file, a
            # run killed between results.h5 and summary.json) is solved again
            append_levels(summary, steps)
            k = min(int(steps.attrs.get("converged", 0)), len(summary.get("steps", [])))
            if k == 0:
                raise InputError("--restart", f"{path}: no converged level to restart from; run it afresh")
            g = steps[f"step_{k:04d}"]
            j = _factoring_level(summary["steps"], k)
            if "restart" not in g:
                raise InputError("--restart", f"{path}: written without restart data (an older version)")
            r = g["restart"]
            fp = h5["model/fingerprint"] if "fingerprint" in h5["model"] else None
            point = RestartPoint(step=k, load_factor=float(g.attrs["load_factor"]),
                                 blocks=r["blocks"][()], increment_blocks=r["increment_blocks"][()],
                                 increment=float(r.attrs["increment"]),
                                 last_increment=float(r.attrs["last_increment"]),
                                 accepted_negative=int(r.attrs["accepted_negative"]),
                                 projection=g["contact/projection"][()] if "contact" in g else None,
                                 status=g["contact/multiplier_active"][()] if "contact" in g else None,
                                 summary={},
                                 fingerprint=None if fp is None else _datasets(fp),
                                 stored_config=stored,
                                 levels=tuple(float(steps[f"step_{i:04d}"].attrs["load_factor"])
                                              for i in range(1, k + 1)),
                                 contact_fields=_contact_fields(g),
                                 previous_contact_fields=(_contact_fields(steps[f"step_{j - 1:04d}"])
                                                          if j > 1 else None),
                                 pointwise_from=(float(r.attrs["fade_forces_pointwise_from"])
                                                 if "fade_forces_pointwise_from" in r.attrs else None),
                                 window_whole_from=(float(r.attrs["search_window_whole_from"])
                                                    if "search_window_whole_from" in r.attrs else None),
                                 settled_increments=int(r.attrs.get("settled_increments", 0)))
    except (OSError, KeyError) as exc:
        raise InputError("--restart", f"{path}: not a readable results file ({exc}); a run killed "
                                      "while writing it leaves it so: run afresh with --output-dir") from None
    summary["steps"] = summary.get("steps", [])[:point.step]
    point.summary = summary
    return point


def read_restart_on_every_rank(directory: str, comm) -> RestartPoint:
    """``read_restart`` on rank 0, its result or its input error on every rank."""
    point, err = None, None
    if comm.rank == 0:
        try:
            point = read_restart(directory)
        except InputError as exc:
            err = (exc.path, exc.message, exc.kind)
    if comm.size > 1:
        point, err = comm.tompi4py().bcast((point, err), root=0)
    if err:
        raise InputError(*err)
    return point


def restart_directory(directory: str, comm) -> str:
    """``directory`` (--restart DIR) if it is one, else InputError on every rank: before the
    output directory is prepared, which would create a mistyped DIR empty.  Collective."""
    err = None
    if comm.rank == 0 and not os.path.isdir(directory):
        what = "not a directory" if os.path.exists(directory) else "no such directory"
        err = f"{directory}: {what} (restart from a run's output directory)"
    if comm.size > 1:
        err = comm.tompi4py().bcast(err, root=0)
    if err:
        raise InputError("--restart", err)
    return directory
