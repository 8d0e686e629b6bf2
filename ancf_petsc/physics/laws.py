"""The material law of a validated config mapping (``config/beams.py``): neo-Hookean, SVK or GOH."""
from __future__ import annotations

from .goh import E_ROUNDING, GOH
from .materials import NeoHookean, StVenantKirchhoff


#: the material registry, by config name (``beams[i].material.model``): how each law is built from
#: a validated config mapping (config/beams.py ``MATERIAL_PARSERS`` validates one per name)
MATERIALS = {
    NeoHookean.name: lambda spec: NeoHookean(spec["mu"], spec["bulk_modulus"]),
    StVenantKirchhoff.name: lambda spec: StVenantKirchhoff(spec["E"], spec["nu"]),
    # e_rounding: no config key, set in code on a parsed spec (a diagnosis; physics/goh.py)
    GOH.name: lambda spec: GOH(spec["mu"], spec["bulk_modulus"], spec["k1"], spec["k2"], spec["kappa"],
                               spec["fibres"], e_rounding=spec.get("e_rounding", E_ROUNDING)),
}


#: the laws with a decoupled volumetric term K/2 (J − 1)², the term ``locking: mixed`` projects
VOLUMETRIC_LAWS = tuple(law.name for law in (NeoHookean, StVenantKirchhoff, GOH) if law.volumetric_term)


def make_material(spec: dict):
    """Material from a validated config mapping; a GOH law still needs its fibre directions
    (``GOH.with_directions``, set up per Gauss point by the model)."""
    return MATERIALS[spec["model"]](spec)
