"""docs/verification.md's tables are what scripts/verification_report.py prints today: the page said
Newton 4/4/4/4 on uniaxial tension and 38/15/27 on the 16-element elastica after the runs gave
4/3/3/3 and 36/16/25."""
import math
import os
import re

import pytest

from helpers import ROOT, load_raw, run_inline

pytestmark = pytest.mark.slow


def _page() -> str:
    with open(os.path.join(ROOT, "docs", "verification.md"), encoding="utf-8") as fh:
        return fh.read().replace("−", "-")


def _rows(text: str, header: str) -> list[list[str]]:
    """The cells of the Markdown table whose header line starts with ``header``."""
    lines = text[text.index(header):].splitlines()[2:]
    rows = []
    for line in lines:
        if not line.startswith("|"):
            break
        rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    return rows


@pytest.fixture(scope="module")
def report() -> str:
    """scripts/verification_report.py's tables (figures to a scratch directory)."""
    import contextlib
    import io
    import tempfile
    from ancf_verify.demos import verification_report as vr
    out = io.StringIO()
    with tempfile.TemporaryDirectory() as tmp, contextlib.redirect_stdout(out):
        vr.uniaxial(tmp, tmp)
        vr.elastica(tmp, tmp)
        vr.pretwisted(tmp, tmp)
    return out.getvalue()


def test_uniaxial_rows_are_the_reports(report):
    ran = {r[0]: r for r in _rows(report, "| load [N] |")}
    page = _rows(_page(), "| load [N] |")
    assert page
    for load, fe, exact, err, its in page:
        assert [fe, exact, its] == [ran[load][1], ran[load][2], ran[load][4]], (load, ran[load])
        assert float(err) < 1e-12 and float(ran[load][3]) < 1e-12


def test_elastica_rows_are_the_reports(report):
    ran = {}
    for ne, pts, _a, *_, eu, ew, its in _rows(report, "| elements | axial points | PL²/EI |"):
        ran.setdefault((ne, pts), []).append((float(eu), float(ew), its))
    page = _rows(_page(), "| elements | axial points | PL²/EI |")
    assert len(page) == len(ran)
    for ne, pts, _a, eu, ew, its in page:
        got = ran[(ne, pts.split()[0])]
        assert [float(x) for x in eu.split(" / ")] == [float(f"{g[0]:.1e}") for g in got], (ne, pts)
        assert [float(x) for x in ew.split(" / ")] == [float(f"{g[1]:.1e}") for g in got], (ne, pts)
        assert its.split(" / ") == [g[2] for g in got], (ne, pts, [g[2] for g in got])


def test_pretwisted_rows_are_the_reports(report):
    ran = [r[:5] for r in _rows(report, "| elements | elongation [mm] |")]
    assert _rows(_page(), "| elements | elongation [mm] |") == ran


def test_newton_history_quoted_is_a_runs(tmp_path):
    """'e.g. ‖F‖ a → b → c at 9 N' is the uniaxial run's residual history at that level."""
    m = re.search(r"‖F‖ ([-\d.e→ ]+) at ([\d.]+) N", " ".join(_page().split()))
    quoted = [float(x) for x in m.group(1).split(" → ")]
    raw = load_raw("uniaxial_neohookean.yaml")
    raw["output"]["vtk"] = False
    s = run_inline(raw, tmp_path)
    F = raw["loads"][0]["traction_force"][0]
    step = next(st for st in s["steps"] if math.isclose(st["load_factor"] * F, float(m.group(2))))
    assert quoted == [float(f"{h:.1e}") for h in step["newton_history"][-1][-len(quoted):]]
