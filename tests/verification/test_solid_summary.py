"""``make verify-solid``'s table (ancf_verify.summary) from the committed CSVs: every reference
of every family is a row, with its convergence and the beams' errors read off the CSVs."""
import math
import os
import shutil
import sys

import pytest

from ancf_verify.cli.summary import main
from ancf_verify.summary import bars, contact, fibres, friction, references, soft_matrix, table
from helpers import ROOT


def test_every_committed_reference_is_a_row():
    refs = references()
    assert len(bars()) == 4 and len(fibres()) == 9 and len(friction()) == 1 and len(soft_matrix()) == 2
    assert {r.name for r in contact()} >= {"three subtendons, sliding, ψ = 45°, clamped roots",
                                           "three subtendons, unilateral, ψ = 45°, clamped roots"}
    assert len(refs) == len({r.name for r in refs})
    for r in refs:
        assert math.isfinite(r.convergence) and 0.0 <= r.convergence < 0.1, r
        assert any(math.isfinite(e) for e in r.errors.values()), r
    lines = table(refs).splitlines()
    assert len(lines) == 2 + len(refs)


def test_the_bars_rows_are_the_csvs_numbers():
    """bar: tension at 4 elements: the CSV's ANCF 2pt rel_error (9.920066e-04) and its
    reference's uncertainty (5.039e-04)."""
    tension = next(r for r in bars() if r.name == "bar: tension")
    assert tension.errors[4] == 9.920066e-04 and tension.convergence == 5.039e-04


def test_the_quick_mode_prints_the_table(capsys):
    assert main(["--quick"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("| reference |") and "three subtendons, Coulomb" in out


@pytest.mark.parametrize("docs", ["missing", "README.md", "empty"])
def test_a_docs_directory_without_references_is_refused(docs, tmp_path, capsys):
    """--quick --docs /nonexistent printed an empty table and exit 0 (a README.md: NotADirectoryError,
    exit 1); now one line naming --docs, exit 2, before any solid is re-solved."""
    (tmp_path / "empty").mkdir()
    path = os.path.join(ROOT, docs) if docs == "README.md" else str(tmp_path / docs)
    with pytest.raises(SystemExit) as exc:
        main(["--quick", "--docs", path])
    assert exc.value.code == 2
    assert capsys.readouterr().err.splitlines() == [
        f"{os.path.basename(sys.argv[0])}: --docs: no reference CSV (solid_comparison.csv, solid_contact.csv, ...) "
        f"in {path!r}; give the directory that holds them (default docs/) (see {os.path.basename(sys.argv[0])} --help)"]


def test_the_checks_read_the_given_docs(tmp_path, monkeypatch, capsys):
    """The re-solves were compared with docs/'s CSVs whatever --docs said (the table read --docs)."""
    import ancf_verify.checks
    shutil.copy(os.path.join(ROOT, "docs", "solid_comparison.csv"), tmp_path)
    seen = []
    monkeypatch.setattr(ancf_verify.checks, "every_check", lambda **kw: seen.append(kw.get("docs")) or [])
    assert main(["--docs", str(tmp_path)]) == 0
    assert seen == [str(tmp_path)] and "bar: tension" in capsys.readouterr().out


def test_a_norm_is_printed_without_a_sign():
    """The bars' and fibre bars' errors are norms |u − u_ref| / |u_ref| (solid_comparison.csv:
    tension, 8 el., 2 points: 1.18e-03 where the beam's |u| is 0.07 % *short* of the solid's) but
    were printed '+0.12 %', as if the beam were that much softer; the signed u_x errors of the
    contact and soft-matrix rows keep their sign."""
    lines = {line.split(" | ")[0][2:]: line for line in table(references()).splitlines()[2:]}
    assert lines["bar: tension"].endswith("| 0.88 % | 0.10 % | 0.12 % | 0.09 % |")
    assert "+" not in lines["fibre bar: goh_twist, K/μ = 50"]
    assert lines["soft-matrix bar (GOH alex set), beams locking: none"].endswith("| +30.39 % | +30.31 % | — |")


def test_a_check_without_its_csv_row_names_the_row(tmp_path):
    """With --docs a run's directory (verify_solid.py --cases tension --out DIR), the bending check
    ended in 'StopIteration: ' (run: exit 1, nothing named); now a SolidError naming CSV and row."""
    from ancf_verify import checks
    from ancf_verify.bars.cases import CASES
    from ancf_verify.stack import SolidError
    lines = open(os.path.join(ROOT, "docs", "solid_comparison.csv")).read().splitlines()
    (tmp_path / "solid_comparison.csv").write_text("\n".join(l for l in lines if not l.startswith("bending,")) + "\n")
    with pytest.raises(SolidError, match=r"solid_comparison.csv: no row 'bending, solid P2 tet, h 8.00 mm' to "
                                         r"re-solve \(a CSV of another run\?\)"):
        checks.bar(next(c for c in CASES if c.key == "bending"), str(tmp_path))
