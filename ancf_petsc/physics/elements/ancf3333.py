"""ANCF 3333 (Nachbagauer et al. 2013, Ebel et al. 2017): the same quadratic axial interpolation
with the linear section field 1, y, z (r, r_y, r_z).

Its nodes keep 3363's 18-DOF block and hold r_yy, r_zz, r_yz at their reference value 0, so its
kinematics are exactly 3333's while 3333 and 3363 beams share one DOF layout (contact between
them, output); its element kernels run on the 27 active DOFs only.  It is prone to Poisson
locking, hence ``ecm`` by default."""
from .ancf3363 import BLOCK
from .base import Element

ELEMENT = Element("3333", BLOCK, vectors=(0, 1, 2), default_locking="ecm", remedies=("none", "ecm"),
                  refused_because="mixed projects J onto 1, y, z, where 3333's J already lies: it changes nothing")
