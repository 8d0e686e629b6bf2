"""The three subtendons with Coulomb friction as 3D solids against ANCF (docs/interface.md)."""
