"""A beam that only unilateral contact holds in some direction is named before the solve
(solving/supports.py, ``lift_off_warnings``): pulled off its neighbour it has nothing holding it,
and the run failed at its first increment with no word of why (Newton stalling at |F| 5e28 N)."""
import copy

from helpers import build_problem, run_inline
from ancf_petsc.solving.supports import check_supports

H, B = 1e-3, 5e-3


def _strips(mode: str, pull: float) -> dict:
    """Two 20 x 5 x 1 mm strips stacked along z: the lower clamped, the upper held along x and y
    at its root and along y at its tip, so that along z only the contact holds it; its tip pulled
    by ``pull`` [N] along z (> 0: off the lower one)."""
    def beam(name, z0, shared):
        pts = [[-B / 2, z0], [B / 2, z0], [B / 2, z0 + H], [-B / 2, z0 + H]]
        names = [name + s for s in ("_bottom", "_right", "_top", "_left")]
        names[shared] = "interface"
        return {"name": name, "elements": 2, "material": {"model": "neo-hookean", "mu": 0.5e6, "bulk_modulus": 1e6},
                "section": {"shape": "outline", "curves": [{"name": n, "points": [pts[i], pts[(i + 1) % 4]]}
                                                          for i, n in enumerate(names)]}}
    return {"name": "lifted", "units": "SI", "geometry": {"length": 0.02, "twist_axis": "origin"},
            "beams": [beam("lower", -H, 2), beam("upper", 0.0, 0)],
            "boundary_conditions": [{"beam": "lower", "node": 0, "fix": "clamped"},
                                    {"beam": "upper", "node": 0, "fix": {"r": "xy"}},
                                    {"beam": "upper", "node": "last", "fix": {"r": "y"}}],
            "loads": [{"beam": "upper", "node": "last", "force": [0.0, 0.0, pull]}],
            "steps": [1.0], "solver": {"min_increment": 0.3},
            "contact": {"mode": mode, "fade_forces": "variational"}}


def test_a_beam_held_only_by_unilateral_contact_is_named_before_the_solve(tmp_path):
    """The upper strip: along z, about x and about y only the contact holds it.  Unilateral: one
    warning naming it and those motions, in summary.json of the run that pulls it off (which
    fails: it is free there).  Sliding holds the interface both ways: no warning; nor with the
    upper strip clamped."""
    P, _ = build_problem(_strips("unilateral", 1e-4))
    (note,) = check_supports(P)
    assert note.startswith("warning: only unilateral contact holds upper (free: translation along z, "
                           "rotation about x, rotation about y)"), note
    s = run_inline(_strips("unilateral", 1e-4), tmp_path / "lifted")
    assert s["status"] == "failed" and note in s["warnings"]
    assert check_supports(build_problem(_strips("sliding", 1e-4))[0]) == []
    clamped = copy.deepcopy(_strips("unilateral", 1e-4))
    clamped["boundary_conditions"][1] = {"beam": "upper", "node": 0, "fix": "clamped"}
    assert check_supports(build_problem(clamped)[0]) == []
