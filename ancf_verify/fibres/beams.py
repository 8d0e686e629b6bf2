"""The fibre bar as ANCF beams in-process (plain, ``locking: mixed``, selective reduced volumetric rule)."""
from __future__ import annotations

import os
import time

from ancf_verify.bars.cases import Case, ancf_config
from ancf_verify.fibres.cases import (ANCF, ANCF_MIXED, ANCF_MODELS, ANCF_VOL, ELEMENTS, STATIONS,
    VOLUMETRIC_DEGREE)
from ancf_verify.fibres.measures import ancf_volumetric_share, section_rotation_deg
from ancf_verify.paths import CONFIGS
from ancf_verify.stack import SolidError


def run_ancf(case: Case, elements: int, tmp: str, model: str = ANCF, load: str = "traction_force",
             pressure_columns: tuple | None = None) -> dict:
    """ANCF 3363, 2 axial Gauss points: end-centroid displacement and end-section rotation at
    every level; at the last, the rotation at the stations and the volumetric energy share
    (``model`` ANCF_VOL: the volumetric term on the section rule of degree VOLUMETRIC_DEGREE,
    ``BeamSpec.volumetric_degree``, a locking diagnosis, no share; ANCF_MIXED: ``locking: mixed``).
    ``load``: the end load's config key, ``traction_force`` (the solid's) or ``force`` (on r);
    ``pressure_columns``: ANCF_MIXED's pressure space (``BeamSpec.pressure_columns``)."""
    import h5py
    from ancf_petsc.config.parse import parse_config
    from ancf_petsc.solving.run import run_model
    out_dir = os.path.join(tmp, f"{case.key}_{elements}_{ANCF_MODELS.index(model):d}_{load}")
    raw = ancf_config(case, elements, 2, out_dir)
    raw["loads"][0] = {"beam": "bar", "node": "last", load: list(case.force)}
    if model == ANCF_MIXED:
        raw["beams"][0]["locking"] = "mixed"
    t0 = time.perf_counter()
    spec = parse_config(raw, base_dir=CONFIGS)
    if model == ANCF_VOL:
        spec.beams[0].volumetric_degree = VOLUMETRIC_DEGREE
    spec.beams[0].pressure_columns = pressure_columns
    res = run_model(spec, log=lambda *_: None)
    wall = time.perf_counter() - t0
    if res.status != "completed":
        raise SolidError(f"ANCF {case.key} {elements} el. failed: {res.message}")
    with h5py.File(os.path.join(out_dir, "results.h5"), "r") as h5:
        q0 = h5["model/reference_nodal_vectors"][:]
        x = h5["model/beams/bar/x_nodes"][:]
        qs = [h5[f"steps/step_{k:04d}/nodal_vectors"][:] for k in range(1, len(case.steps) + 1)]
    every = (len(x) - 1) // STATIONS
    levels = [{"load": lvl * case.force[0], "u": q[-1, 0] - q0[-1, 0], "rot": section_rotation_deg(q[-1:], q0[-1:])[0]}
              for lvl, q in zip(case.steps, qs)]
    levels[-1]["along"] = section_rotation_deg(qs[-1][every::every], q0[every::every])
    if model != ANCF_VOL:
        levels[-1]["vol_share"] = ancf_volumetric_share(raw, qs[-1])
    return {**levels[-1], "model": model, "res": f"{elements} el.",
            "dofs": int(res.summary["dofs"]),
            "its": int(sum(st["iterations"] for st in res.summary["steps"])), "wall": wall,
            "levels": levels, "field_err": float("nan"), "q": qs[-1]}


def ancf_runs(case: Case, tmp: str) -> list[dict]:
    """The ANCF runs of one case: plain and ``locking: mixed`` at every element count, the
    degree-2 diagnosis at the two finest."""
    runs = [run_ancf(case, n, tmp, model) for model in (ANCF, ANCF_MIXED) for n in ELEMENTS]
    return runs + [run_ancf(case, n, tmp, ANCF_VOL) for n in ELEMENTS[-2:]]
