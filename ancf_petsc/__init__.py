"""ancf-petsc: ANCF 3363 continuum beams for tendon mechanics, assembled and solved with PETSc.

Implements Obrezkov, Finni, Matikainen (2022), Materials 15:8906.
"""
from .version import __version__
