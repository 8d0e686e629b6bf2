"""PETSc options read from files get the command line's checks (issue 25): a missing options file
or a bad value inside one is one line naming the file, its line and the option, exit 2, before
PETSc starts (no PETSc banner, no traceback, nothing written)."""
from __future__ import annotations

import pytest

from helpers import solve_cli, write_config
from test_edges import TIMEOUT, assert_one_line, tiny

from ancf_petsc.config.options_files import check_all_options

OWN = ("--output-dir", "--restart", "--quiet")


def _opts(tmp_path, text: str, name: str = "o.opts") -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


@pytest.mark.parametrize("text,words", [
    ("-snes_rtol abc\n", ("-snes_rtol abc", "o.opts line 1", "expected a number")),
    ("# tuned\n-ksp_type gmres\n-pc_type LU  # comment\n", ("o.opts line 3", "lower case: lu")),
    ("-snes_max_it 1e2\n", ("-snes_max_it 1e2", "expected an integer")),
    ("-snes_rtol 1e-8 -ksp_type gmres\n", ("o.opts line 1", "one option per line")),
    ("snes_rtol 1e-8\n", ("'snes_rtol' is not an option",)),
    ("alias -tol -snes_rtol\n-tol x\n", ("-snes_rtol x", "line 2")),
    ("-restart out\n", ("-restart out", "two dashes (--restart)")),
])
def test_options_file_values_are_checked(tmp_path, text, words):
    line = check_all_options(["-options_file", _opts(tmp_path, text)], OWN, environ={})
    assert line is not None
    for w in words:
        assert w in line, line


def test_good_files_nested_files_and_the_environment(tmp_path):
    inner = _opts(tmp_path, "-snes_max_it 2.5\n", "inner.opts")
    outer = _opts(tmp_path, f"-snes_rtol 1e-9\t\r\n-options_file {inner}\n", "outer.opts")
    assert "inner.opts line 1" in check_all_options(["-options_file", outer], OWN, environ={})
    good = _opts(tmp_path, "-snes_rtol 1e-9 # fine\n\n-snes_monitor\n-ksp_type gmres\n")
    assert check_all_options(["-options_file", good], OWN, environ={}) is None
    line = check_all_options([], OWN, environ={"PETSC_OPTIONS": "-snes_max_it 1.5"})
    assert "PETSC_OPTIONS" in line and "-snes_max_it 1.5" in line
    assert "needs the path" in check_all_options(["-options_file"], OWN, environ={})
    assert "is a directory" in check_all_options(["-options_file", str(tmp_path)], OWN, environ={})


@pytest.mark.parametrize("args,stray", [
    (["other.yaml"], "other.yaml"), (["snes_max_it", "3"], "snes_max_it"), (["-snes_max_it", "3", "4"], "4"),
    (["-snes_monitor", "-snes_max_it", "30"], None), (["-snes_divergence_tolerance", "-1"], None),
    (["-snes_monitor", "ascii:m.txt", "-help"], None),
])
def test_a_word_petsc_would_skip_is_refused(args, stray):
    """PETSc skips a word that is neither an option nor its value: a second config or a
    dash-less option was ignored without a word (max_it stayed 15)."""
    line = check_all_options(args, OWN, environ={})
    if stray is None:
        assert line is None, line
    else:
        assert line.startswith(f"{stray}: neither an option nor an option's value"), line


def test_stray_words_on_the_command_lines(tmp_path, capsys):
    raw = tiny()
    raw["output"]["dir"] = str(tmp_path / "out")
    cfg = write_config(raw, tmp_path / "c.yaml")
    assert_one_line(solve_cli(cfg, extra=["--quiet", "other.yaml"], timeout=TIMEOUT), 2,
                    "ancf-solve: other.yaml: neither an option nor an option's value")
    assert not (tmp_path / "out").exists()
    from apps.ancf_study import main
    with pytest.raises(SystemExit) as exc:                  # before PETSc starts, nothing solved
        main([cfg, "snes_max_it", "3"])
    assert exc.value.code == 2
    assert "ancf-study: snes_max_it: neither an option" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:                  # named as given, not -study1_snes_max_it
        main([cfg, "-snes_max_it", "abc"])
    assert exc.value.code == 2
    assert "ancf-study: PETSc option -snes_max_it abc: expected an integer" in capsys.readouterr().err


@pytest.mark.parametrize("case", ["missing", "bad value"])
def test_options_file_problems_on_the_command_line(tmp_path, case):
    raw = tiny()
    raw["output"]["dir"] = str(tmp_path / "out")
    cfg = write_config(raw, tmp_path / "c.yaml")
    path = str(tmp_path / "none.opts") if case == "missing" else _opts(tmp_path, "-snes_rtol abc\n")
    p = solve_cli(cfg, extra=["--quiet", "-options_file", path], timeout=TIMEOUT)
    words = ("-options_file", "no such file") if case == "missing" else ("o.opts line 1", "-snes_rtol abc")
    line = assert_one_line(p, 2, *words)
    assert "default" not in line and "refused the solver" not in line
    assert not (tmp_path / "out").exists()
