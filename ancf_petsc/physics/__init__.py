"""The continuum mechanics of one beam, in numpy (no PETSc, no config): the elements as data
(``elements``: one module per element, its nodal vectors as section monomials, axial nodes and
shape functions), the paper's ANCF 3363 (``element3363``: shape functions, eqs. 1-5),
cross-sections (``section``, ``spline``, ``polygon``, ``sections_file``) and their Gauss-Green cubature (``cubature``, eqs. 9-11), the
materials (``materials``: neo-Hookean, eq. 14; St. Venant-Kirchhoff), the vectorised element
kernels (``kernels``: internal forces and tangents over elements x Gauss points), the pretwisted
reference geometry (``geometry``), rigid modes (``rigid``) and exact solutions for verification
(``reference_solutions``)."""

#: the sub-modules (imported on use: a plain import of the package loads none of them)
__all__ = ["cubature", "element3363", "elements", "fibres", "geometry", "goh", "kernels", "laws", "materials",
           "polygon", "reference_solutions", "rigid", "section", "sections_file", "spline"]
