"""The material law of a validated config mapping (``config/beams.py``): neo-Hookean, SVK or GOH."""
from __future__ import annotations

from .goh import GOH
from .materials import NeoHookean, StVenantKirchhoff


def make_material(spec: dict):
    """Material from a validated config mapping; a GOH law still needs its fibre directions
    (``GOH.with_directions``, set up per Gauss point by the model)."""
    if spec["model"] == "neo-hookean":
        return NeoHookean(spec["mu"], spec["bulk_modulus"])
    if spec["model"] == "goh":
        return GOH(spec["mu"], spec["bulk_modulus"], spec["k1"], spec["k2"], spec["kappa"],
                   spec["fibres"])
    return StVenantKirchhoff(spec["E"], spec["nu"])
