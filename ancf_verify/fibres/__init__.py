"""The helical-fibre (GOH) bar as a 3D solid against ANCF (docs/fibres.md)."""
