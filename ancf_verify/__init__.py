"""ancf_verify: the 3D-solid references of ancf_petsc (dolfinx + gmsh) and their comparisons with the
beams, one job per module (docs/verification.md, "3D solids"). The library never imports it.

Sub-packages: ``bars`` (straight and twisted bars), ``contact`` (three subtendons, contact by exact
multipliers), ``friction`` (the same with Coulomb friction), ``fibres`` (helical GOH fibres),
``soft_matrix`` (a soft matrix with stiff fibres), ``studies`` (diagnostics on them and on the
beams), ``bench`` (the beams' benchmarks), ``demos`` (demonstrations and reports), ``cli`` (the
command lines that scripts/ calls); shared: ``stack``, ``newton``, ``convergence``, ``paths``."""
