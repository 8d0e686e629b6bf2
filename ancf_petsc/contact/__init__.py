"""Surface-to-surface contact between beams (paper §5): interfaces, quadrature points, closest-point
projection, gap derivatives, the multiplier (pressure) space and the contact laws.  No PETSc here:
``Contact`` fills local arrays and returns dense blocks that the assembly layer inserts."""
from .contact import Contact, build_contact, decide_kept, forget_evaluation, hold_bounds, pending_status
from .multipliers import reference_stiffness
from .interfaces import ContactSetupError, Interface, find_interfaces
from .laws import LAWS
from .tangential import TANGENTIAL_LAWS

__all__ = ["Contact", "ContactSetupError", "Interface", "LAWS", "TANGENTIAL_LAWS", "build_contact", "decide_kept",
           "find_interfaces",
           "forget_evaluation", "hold_bounds", "pending_status", "reference_stiffness"]
