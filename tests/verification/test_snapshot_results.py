"""scripts/snapshot_results.py: a misspelt --only ran nothing, wrote '{}' and exited 0, and
--compare against a snapshot without the case compared nothing and exited 0 ('no difference')."""
import json
import sys

import pytest


def _main(monkeypatch, *argv) -> int:
    from ancf_verify.demos import snapshot_results
    monkeypatch.setattr(sys, "argv", ["snapshot_results.py", *argv])
    return snapshot_results.main()


def test_unknown_case_is_refused_with_the_cases(monkeypatch, capsys, tmp_path):
    with pytest.raises(SystemExit) as exc:
        _main(monkeypatch, "--only", "psi0_sliding", "--write", str(tmp_path / "s.json"))
    err = capsys.readouterr().err.splitlines()[-1]
    assert exc.value.code == 2 and not (tmp_path / "s.json").exists()
    assert err.startswith("snapshot_results.py: error: --only: no case 'psi0_sliding'; cases: table1_psi0, "), err


@pytest.mark.slow
def test_a_case_missing_from_the_snapshot_fails_the_comparison(monkeypatch, capsys, tmp_path):
    (tmp_path / "before.json").write_text(json.dumps({}))
    assert _main(monkeypatch, "--only", "table2_psi0_1el", "--compare", str(tmp_path / "before.json")) == 1
    assert "table2_psi0_1el              not in" in capsys.readouterr().out
