"""scripts/accuracy_demo.py times its scenes after one untimed run: the process's start-up (0.3 s)
landed in the first scene's ladder, so uniaxial tension's 1-2-4 ladder (0.5 s) came out dearer
than one 64-element run (0.4 s), 'cheaper: NO'."""
import sys

import pytest

pytestmark = pytest.mark.slow


def test_the_first_solve_is_an_untimed_warm_up(tmp_path, monkeypatch):
    import ancf_petsc.api
    from ancf_verify.demos import accuracy_demo
    solve, dirs = ancf_petsc.api.solve, []

    def recording(spec, **kw):
        dirs.append(spec.output.dir)
        return solve(spec, **kw)
    monkeypatch.setattr(ancf_petsc.api, "solve", recording)
    out = tmp_path / "accuracy_demo.md"
    monkeypatch.setattr(sys, "argv", ["accuracy_demo.py", "--quick", "--out", str(out),
                                      "--work", str(tmp_path / "work")])
    assert accuracy_demo.main() == 0
    assert dirs[0].endswith("warm_up") and len(dirs) == 1 + 2 * 2, dirs
    rows = [line.split(" | ") for line in out.read_text().splitlines()[4:]]
    assert [r[0] for r in rows] == ["| uniaxial tension", "| bending (K/mu = 50)"]
    assert all(r[-2] == "yes" for r in rows), rows   # the tolerance met
