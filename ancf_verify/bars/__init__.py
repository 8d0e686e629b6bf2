"""Straight and pretwisted neo-Hookean bars as 3D solids against ANCF (docs/solid_comparison.md)."""
