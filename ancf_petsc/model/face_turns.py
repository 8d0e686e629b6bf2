"""A prescribed slope (``displacement`` on r_y or r_z) of an element with a cubic or quartic
section field (33103, 33153), whose higher vectors the support leaves free.

r_y and r_z are the coefficients of y and z in the section field, the turn of the end face only
where nothing else moves it the same way: in 3363 the quadratic vectors are orthogonal to them
on a symmetric section, but a cubic vector is not (∫ z · z³ dA ≠ 0).  Left free, the face warps
around the prescribed slope: a bar bent by an end turn φ (r_z·e_x = −φ, 8-32 elements, plane
root) carried 0.9947 E I φ / L on 33103 and 0.978 on 33153, an answer that depends on the
element's order; 1.0000 on 3363 and on both with the higher vectors' x components held."""
from __future__ import annotations

from ..physics.elements import ELEMENTS

__all__ = ["slope_warnings"]


def _held(spec, bc) -> set[tuple[int, int]]:
    """(vector, component) held or moved at ``bc``'s node by any support."""
    out = set()
    for other in spec.boundary_conditions:
        if (other.beam, other.node) == (bc.beam, bc.node):
            out |= set(other.dofs) | {(v, c) for v, c, _ in other.displacement}
    return out


def slope_warnings(spec) -> list[str]:
    """One warning per support that prescribes a slope component whose higher vectors' same
    component it leaves free (module docstring)."""
    out = []
    for bc in spec.boundary_conditions:
        block = ELEMENTS[spec.beams[bc.beam].element].block
        higher = [k for k, (i, j) in enumerate(block.monomials) if i + j >= 3]
        held = _held(spec, bc)
        for v, c in sorted({(v, c) for v, c, _ in bc.displacement if sum(block.monomials[v]) == 1}):
            free = [block.names[k] for k in higher if (k, c) not in held]
            if free:
                axis = "xyz"[c]
                out.append(f"warning: {bc.path}.displacement.{block.names[v]}.{axis}: on element "
                           f"{spec.beams[bc.beam].element} {block.names[v]} is the coefficient of {'yz'[v - 1]} in the "
                           f"section field, not the end face's turn: the free {axis} components of {', '.join(free)} "
                           f"let the face warp around it (a bar bent by an end turn: 0.5 % softer on 33103, 2.2 % "
                           f"on 33153); hold them too, fix: {{{', '.join(f'{n}: {axis}' for n in free)}}}")
                break
    return out
