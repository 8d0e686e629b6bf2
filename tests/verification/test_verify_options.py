"""Bad options of the 3D-solid command lines (ancf_verify.cli): one line naming the option, exit 2,
before any solid is meshed or solved."""
import os
import subprocess
import sys

import pytest

from helpers import MPI_ENV, ROOT


@pytest.mark.parametrize("script, argv, want", [
    ("verify_solid_contact.py", ["--h=-2e-3"], "argument --h: mesh sizes must be > 0; got '-2e-3'"),
    ("verify_solid_contact.py", ["--h", "2e-3,0"], "argument --h: mesh sizes must be > 0; got '0'"),
    ("verify_solid_friction.py", ["--h-more", "2mm"],
     "argument --h-more: expected a mesh size > 0, e.g. 2e-3; got '2mm'"),
    ("solid_friction_across.py", ["--h", ","],
     "argument --h: expected mesh sizes > 0 separated by commas, e.g. 2e-3,1.4e-3; got ','"),
    ("verify_solid_soft_matrix.py", ["--h", "2", "-1"], "argument --h: mesh sizes must be > 0; got '-1'"),
    ("verify_solid_soft_matrix.py", ["--h", "2e-3"], "argument --h: mesh sizes are in mm here (the other solid "
                                                     "commands take m), e.g. 2 for 2 mm; got '2e-3'"),
])
def test_a_mesh_size_at_or_below_zero_is_refused_by_its_option(script, argv, want, tmp_path):
    """verify_solid_contact.py --h=-2e-3 went on to gmsh, which aborted the whole process
    ('terminate called after throwing ...', a C++ backtrace, exit 134); '2mm' ended in
    'ValueError: could not convert string to float', exit 1, naming no option.  The soft-matrix bar
    takes mm: --h 2e-3 (2 mm in the other commands' m) asked gmsh for 2 µm tetrahedra (hours, memory)."""
    p = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", script), *argv, "--out", str(tmp_path)]
                       if script != "solid_friction_across.py" else
                       [sys.executable, os.path.join(ROOT, "scripts", script), *argv],
                       capture_output=True, text=True, timeout=120, env={**os.environ, **MPI_ENV})
    assert p.returncode == 2, (p.returncode, p.stderr[-600:])
    assert p.stderr.splitlines() == [f"{script}: {want} (see {script} --help)"], p.stderr


def test_the_meshes_refuse_a_size_gmsh_cannot_take():
    """The Python API (run_solid, tendon_mesh) is checked too: a SolidError line, not gmsh's abort."""
    from ancf_verify.bars.cases import CASES
    from ancf_verify.bars.mesh import solid_mesh
    from ancf_verify.contact.mesh import tendon_mesh
    from ancf_verify.stack import SolidError
    with pytest.raises(SolidError, match=r"mesh size h must be > 0 \[m\]; got -0.002"):
        solid_mesh(CASES[0], None, -2e-3)
    with pytest.raises(SolidError, match="got 0.0"):
        tendon_mesh(None, 0.0, 45.0)


@pytest.mark.parametrize("argv, want", [
    (["--cases", "tensoin"], "--cases: unknown case(s) tensoin; choose from tension, bending, pretwisted, soleus; "
                             "got 'tensoin'"),
    (["--cases", ","], "--cases: no case; choose from tension, bending, pretwisted, soleus; got ','"),
    (["--ancf-repeats", "0"], "argument --ancf-repeats: expected a positive integer; got 0"),
    (["--quad-degree", "-1"], "argument --quad-degree: expected a positive integer; got -1"),
    (["--replot", "--out", "/nonexistent"], "--replot: no solid_comparison.csv in --out '/nonexistent'; "
                                            "give the directory of a run's CSV"),
    (["--cases", "tension"], "--cases: a run into docs/ writes solid_comparison.csv and .md with its cases alone "
                             "(the committed references of the others would go); give --out DIR; got 'tension'"),
])
def test_verify_solid_names_the_bad_option(argv, want, capsys):
    """verify_solid.py --cases tensoin said 'unknown case(s) ['tensoin']' naming no option, exit 1;
    --cases , ended in 'StopIteration', --ancf-repeats 0 in an AttributeError after the solid's JIT,
    --replot --out /nonexistent in a FileNotFoundError (exit 1 each); --cases tension into docs/
    replaced docs/solid_comparison.csv and .md by the tension rows alone. Now one line, exit 2."""
    from ancf_verify.cli.bars import main
    with pytest.raises(SystemExit) as exc:
        main(argv)
    prog = os.path.basename(sys.argv[0])
    assert exc.value.code == 2 and capsys.readouterr().err.splitlines() == [f"{prog}: {want} (see {prog} --help)"]


@pytest.mark.parametrize("command, csv_name", [("fibres", "solid_fibres.csv"), ("soft_matrix", "solid_soft_matrix.csv")])
def test_a_run_into_another_out_leaves_the_committed_page_alone(command, csv_name, tmp_path):
    """verify_solid_fibres.py / verify_solid_soft_matrix.py with --out elsewhere (a --quick smoke
    run, a --replot of another CSV) still rewrote the block of docs/fibres.md from that run's rows;
    the block now goes to a copy of the page in --out unless --doc names a page."""
    import importlib
    import shutil
    page = os.path.join(ROOT, "docs", "fibres.md")
    before = os.stat(page).st_mtime_ns
    shutil.copy(os.path.join(ROOT, "docs", csv_name), tmp_path)
    assert importlib.import_module(f"ancf_verify.cli.{command}").main(["--replot", "--out", str(tmp_path)]) == 0
    assert os.stat(page).st_mtime_ns == before
    assert open(tmp_path / "fibres.md").read() == open(page).read()


@pytest.mark.parametrize("command, argv, want", [
    ("contact", ["--laws", "slidng"], "--laws: expected sliding and/or unilateral separated by commas; got 'slidng'"),
    ("friction", ["--h", "2e-3,1.4e-3", "--h-interface", "1e-3"],
     "--h-interface: one size >= 0 per --h (2; 0: uniform); got '1e-3'"),
    ("friction", ["--h-interface=-7e-4"], "--h-interface: one size >= 0 per --h (3; 0: uniform); got '-7e-4'"),
    ("friction", ["--h-interface", "x"],
     "--h-interface: expected sizes [m] separated by commas, e.g. 1e-3,7e-4; got 'x'"),
])
def test_a_bad_law_or_local_size_is_refused_before_solving(command, argv, want, tmp_path, capsys):
    """verify_solid_contact.py --laws slidng said "unknown law(s) ['slidng']" (exit 1, no option
    named) after loading the stack; verify_solid_friction.py's --h-interface count was checked only
    after the friction tangent's finite-difference self-test (a minute), exit 1, and a negative size
    was taken for 'uniform' without a word."""
    import importlib
    with pytest.raises(SystemExit) as exc:
        importlib.import_module(f"ancf_verify.cli.{command}").main([*argv, "--out", str(tmp_path)])
    prog = os.path.basename(sys.argv[0])
    assert exc.value.code == 2 and capsys.readouterr().err.splitlines() == [f"{prog}: {want} (see {prog} --help)"]


def test_verify_solid_replots_into_a_new_directory(tmp_path):
    """verify_solid.py --replot --out DIR (DIR holding a copy of solid_comparison.csv) ended in
    'FileNotFoundError: ... DIR/figures/solid_vs_ancf.png', exit 1: figures/ was not made."""
    import shutil

    from ancf_verify.cli.bars import main
    shutil.copy(os.path.join(ROOT, "docs", "solid_comparison.csv"), tmp_path)
    assert main(["--replot", "--out", str(tmp_path)]) == 0
    assert os.path.getsize(tmp_path / "figures" / "solid_vs_ancf.png") > 0


def test_a_quick_smoke_run_does_not_write_over_the_committed_references(capsys):
    """verify_solid.py --quick (and verify_solid_fibres.py / verify_solid_contact.py --quick) wrote
    their coarse rows over docs/solid_comparison.csv and .md (the fibres: docs/solid_fibres.csv and
    the block of docs/fibres.md), the committed references that make verify-solid and the docs tests
    read; without --out a smoke run now writes to results/<command>_quick/ (git ignores results/)."""
    from ancf_verify.cli import out_dir
    from ancf_verify.cli.bars import main
    assert out_dir(None, False, "verify_solid") == os.path.join(ROOT, "docs")
    assert out_dir(None, True, "verify_solid") == os.path.join(ROOT, "results", "verify_solid_quick")
    assert out_dir("/tmp/x", True, "verify_solid") == "/tmp/x"
    with pytest.raises(SystemExit):
        main(["--quick", "--replot"])
    assert f"in --out '{os.path.join(ROOT, 'results', 'verify_solid_quick')}'" in capsys.readouterr().err


def test_the_soft_matrix_bar_says_a_missing_dolfinx_before_its_beams_run(tmp_path):
    """verify_solid_soft_matrix.py without dolfinx ran its eight beam columns first (minutes on the
    shared cores) and only then said 'dolfinx/gmsh missing'; --profile 0 was taken for no --profile
    and started the whole 26-minute study."""
    code = ("import sys; sys.modules['dolfinx'] = None\nfrom ancf_verify.cli import run\n"
            f"sys.exit(run('soft_matrix', 'verify_solid_soft_matrix', ['--out', {str(tmp_path)!r}]))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, cwd=ROOT,
                       env={**os.environ, **MPI_ENV})
    assert p.returncode == 1 and "[ANCF]" not in p.stdout, (p.stdout[-500:], p.stderr[-500:])
    assert p.stderr.splitlines() == ["verify_solid_soft_matrix: dolfinx/gmsh missing (import of dolfinx halted; "
                                     "None in sys.modules); run: bash scripts/setup_solid.sh"]
    q = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "verify_solid_soft_matrix.py"), "--profile", "0"],
                       capture_output=True, text=True, timeout=120, env={**os.environ, **MPI_ENV})
    assert q.returncode == 2 and "argument --profile: mesh sizes must be > 0; got '0'" in q.stderr, q.stderr


@pytest.mark.parametrize("command, argv, want", [
    ("contact", ["--psi", "45deg"], "argument --psi: expected numbers separated by commas, e.g. 10,20; got '45deg'"),
    ("contact", ["--elements", "2,0"], "argument --elements: expected a positive integer; got 0"),
    ("friction", ["--elements", "4,x"], "argument --elements: expected a positive integer; got 'x'"),
    ("friction", ["--loads", "10N"], "argument --loads: expected numbers separated by commas, e.g. 10,20; got '10N'"),
])
def test_a_bad_list_option_is_refused_before_solving(command, argv, want, tmp_path, capsys):
    """verify_solid_contact.py --psi 45deg said 'ValueError: could not convert string to float',
    naming no option (exit 1); verify_solid_friction.py read --elements only after its solid runs
    (hours), then 'ValueError: invalid literal for int()'."""
    import importlib
    with pytest.raises(SystemExit) as exc:
        importlib.import_module(f"ancf_verify.cli.{command}").main([*argv, "--out", str(tmp_path)])
    prog = os.path.basename(sys.argv[0])
    assert exc.value.code == 2 and capsys.readouterr().err.splitlines() == [f"{prog}: {want} (see {prog} --help)"]


def test_the_friction_study_makes_its_out_directory(tmp_path, capsys):
    """verify_solid_friction.py --out NEW ran its first column (a solid run: hours) and then failed to
    save it: 'FileNotFoundError: ... NEW/solid_friction.csv'. Beams only, 4 elements: seconds."""
    pytest.importorskip("dolfinx")
    from ancf_verify.cli.friction import main
    out = tmp_path / "new"
    assert main(["--no-selftest", "--no-solid", "--no-checks", "--psi", "45", "--elements", "4",
                 "--ancf-augmentations", "default", "--profiles", "", "--out", str(out)]) == 0
    assert (out / "solid_friction.csv").read_text().count("ANCF") >= 13


def test_an_ancf_src_without_the_package_is_refused(tmp_path):
    """verify_solid_contact.py --ancf-src DIR put DIR first on sys.path whether or not it held
    ancf_petsc: with DIR/configs/ but no package the columns were this checkout's, recorded in the
    CSV under --ancf-label as the export's (with neither, a section file error deep in the run)."""
    (tmp_path / "configs").mkdir()
    p = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "verify_solid_contact.py"), "--ancf-src",
                        str(tmp_path), "--out", str(tmp_path / "out")], capture_output=True, text=True, timeout=120,
                       env={**os.environ, **MPI_ENV})
    prog = "verify_solid_contact.py"
    assert p.returncode == 2 and p.stderr.splitlines() == [
        f"{prog}: --ancf-src: no ancf_petsc package in {str(tmp_path)!r} (this checkout's would be solved under "
        f"its label); give the directory of an export of a commit (see {prog} --help)"], p.stderr


def test_soft_matrix_makes_its_out_directory_before_solving(tmp_path, monkeypatch, capsys):
    """verify_solid_soft_matrix.py --out NEW wrote its CSV into NEW only at the end, and NEW was
    never made: FileNotFoundError after the solid's 26 minutes; --ancf-only into a directory without
    the CSV it merges into failed there too.  Now --out is made before anything is solved, and the
    merge's missing CSV is refused at once (exit 2)."""
    from ancf_verify.cli import soft_matrix

    class Solving(Exception):
        pass

    def solve(*_):
        raise Solving

    monkeypatch.setattr(soft_matrix, "import_stack", solve)
    new = tmp_path / "new" / "out"
    with pytest.raises(Solving):
        soft_matrix.main(["--out", str(new)])
    assert new.is_dir()
    monkeypatch.setattr(soft_matrix, "beam_runs", solve)
    with pytest.raises(SystemExit) as exc:
        soft_matrix.main(["--ancf-only", "--out", str(tmp_path / "other")])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "--ancf-only merges into" in err and "does not exist" in err
