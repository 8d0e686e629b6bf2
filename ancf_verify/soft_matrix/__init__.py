"""The soft-matrix bar as a 3D solid against ANCF (docs/fibres.md, soft matrix)."""
