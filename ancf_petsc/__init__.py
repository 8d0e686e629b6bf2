"""ancf-petsc: ANCF 3363 continuum beams for tendon mechanics, assembled and solved with PETSc.

Implements Obrezkov, Finni, Matikainen (2022), Materials 15:8906.  Kernels (element, material,
section cubature, contact) are pure numpy; only ``assembly`` and ``solver`` touch PETSc.
"""
__version__ = "0.1.0"
