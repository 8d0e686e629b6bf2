"""Messages that must be true (issue 25): a dangling symlink, the root directory or an empty path
as output directory, a pipe as config, a YAML list as the whole config, the run's first line, and
a MATLAB-style CSV outline.  One line each, exit 2, nothing written."""
from __future__ import annotations

import os
import subprocess

import pytest

from helpers import CONFIGS, MPI_ENV, ROOT, VENV_BIN, solve_cli, write_config
from test_edges import TIMEOUT, assert_one_line, tiny

from ancf_petsc.io.files import OutputError, prepare_output_dir


@pytest.mark.parametrize("case,words", [
    ("dangling link", ("dangling symbolic link (to ", "nowhere", "create its target")),
    ("under a dangling link", ("dangling symbolic link (to ", "nowhere")),
    ("root", ("is the root directory",)),
    ("root, spelt otherwise", ("is the root directory",)),
    ("empty", ("empty path",)),
])
def test_output_dir_messages(tmp_path, case, words):
    os.symlink(tmp_path / "nowhere", tmp_path / "link")
    path = {"dangling link": str(tmp_path / "link"), "under a dangling link": str(tmp_path / "link" / "sub"),
            "root": "/", "root, spelt otherwise": "/tmp/../", "empty": ""}[case]
    with pytest.raises(OutputError) as info:
        prepare_output_dir(path)
    for w in words:
        assert w in str(info.value), str(info.value)
    assert "a file is in the way" not in str(info.value)
    assert not (tmp_path / "nowhere").exists()


def test_empty_output_dir_and_a_piped_config_on_the_command_line(tmp_path):
    raw = tiny()
    raw["output"]["dir"] = str(tmp_path / "out")
    cfg = write_config(raw, tmp_path / "c.yaml")
    p = solve_cli(cfg, extra=["--output-dir", "", "--quiet"], timeout=TIMEOUT)
    assert_one_line(p, 2, "--output-dir: an empty path")
    assert not (tmp_path / "out").exists()
    with open(cfg) as fh:                      # `cat c.yaml | ancf-solve /dev/stdin`
        p = subprocess.run([os.path.join(VENV_BIN, "ancf-solve"), "/dev/stdin", "--quiet"],
                           input=fh.read(), capture_output=True, text=True,
                           env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT), timeout=TIMEOUT)
    line = assert_one_line(p, 2, "/dev/stdin", "pipes are not supported", "write it to a file")
    assert "no such config file" not in line
    assert not (tmp_path / "out").exists()


def test_a_yaml_list_as_config_names_each_key_once(tmp_path):
    from ancf_petsc.config.parse import load_config
    from ancf_petsc.config.values import ConfigError
    (tmp_path / "list.yaml").write_text("- a\n- b\n")
    with pytest.raises(ConfigError) as info:
        load_config(str(tmp_path / "list.yaml"))
    text = str(info.value)
    keys = text.split("keys ", 1)[1].split(";", 1)[0].split(", ")
    assert len(keys) == len(set(keys)) and keys[:4] == ["name", "geometry", "beams", "steps"], text
    assert "got list" in text


def test_the_first_line_of_a_contact_run_is_the_model_header(tmp_path):
    p = solve_cli(os.path.join(CONFIGS, "bundle_hex7.yaml"),
                  extra=["--output-dir", str(tmp_path / "out"), "-snes_max_it", "30"], timeout=TIMEOUT)
    assert p.returncode == 0, p.stderr
    lines = p.stdout.splitlines()
    assert lines[0].startswith("[ancf] bundle_hex7: 7 beam(s), 28 elements"), lines[:3]
    contact = [i for i, ln in enumerate(lines) if ln.startswith("[ancf]   contact:")]
    beams = [i for i, ln in enumerate(lines) if ln.startswith("[ancf]   beam ")]
    assert contact and beams and contact[0] > beams[-1]


@pytest.mark.parametrize("text", ["0.0, 0.0;\n1.0, 0.0;\n1.0, 1.0;\n0.0, 1.0;\n",
                                  "0 0;\n1 0;\n1 1;\n0 1;\n", "u;v\n0;0;\n1;0;\n1;1;\n0;1;\n"])
def test_matlab_row_ends_in_a_csv_outline_are_read(tmp_path, text):
    from ancf_petsc.outline_formats.point_list import read_point_list
    (tmp_path / "o.csv").write_text(text)
    assert read_point_list(str(tmp_path / "o.csv")).points.tolist() == \
        [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]


def test_a_csv_outline_with_a_byte_order_mark_keeps_its_first_point(tmp_path):
    """Excel's 'CSV UTF-8' starts with a BOM: '\\ufeff0,0' was taken for a header and dropped, so a
    4-point rectangle 6 x 3 mm became a triangle (18 -> 9 mm^2) with no word."""
    from ancf_petsc.outline_formats.point_list import read_point_list
    (tmp_path / "o.csv").write_bytes(b"\xef\xbb\xbf0,0\r\n6,0\r\n6,3\r\n0,3\r\n")
    assert read_point_list(str(tmp_path / "o.csv")).points.tolist() == [[0, 0], [6, 0], [6, 3], [0, 3]]


def test_a_csv_outline_that_is_not_utf8_is_one_line(tmp_path):
    """A Latin-1 header 'y (\\xb5m)' stopped ancf-solve with a UnicodeDecodeError traceback."""
    from ancf_petsc.outline_formats import OutlineReadError
    from ancf_petsc.outline_formats.point_list import read_point_list
    (tmp_path / "o.csv").write_bytes(b"y (\xb5m),z (\xb5m)\n0,0\n6,0\n6,3\n0,3\n")
    with pytest.raises(OutlineReadError, match=r"o\.csv line 1: byte 0xb5 is not UTF-8 text; save the file as UTF-8"):
        read_point_list(str(tmp_path / "o.csv"))


def test_rejected_csv_lines_are_named(tmp_path):
    from ancf_petsc.outline_formats import OutlineReadError
    from ancf_petsc.outline_formats.point_list import read_point_list
    (tmp_path / "o.csv").write_text("0|0\n1|0\n1|1\n0|1\n")
    with pytest.raises(OutlineReadError) as info:
        read_point_list(str(tmp_path / "o.csv"))
    assert "o.csv line 2" in str(info.value) and "is not two numbers" in str(info.value)
    assert "0 points" not in str(info.value)


def test_an_underscore_in_a_csv_outline_number_is_refused(tmp_path):
    """float('1_0') is 10: an outline point '1_0, 0' was read at u = 10 with no word."""
    from ancf_petsc.outline_formats import OutlineReadError
    from ancf_petsc.outline_formats.point_list import read_point_list
    (tmp_path / "o.csv").write_text("0, 0\n1_0, 0\n1, 1\n0, 1\n")
    with pytest.raises(OutlineReadError, match=r"o\.csv line 2: \['1_0', '0'\] is not two numbers u, v "
                                               r"\(an underscore in a number: write 10 or 1\.0, not 1_0\)"):
        read_point_list(str(tmp_path / "o.csv"))


def test_a_yaml_outline_file_with_keys_beside_its_points_is_refused(tmp_path):
    """axes: [y, -z] and units: um beside the points of a YAML point file were not read: the
    triangle came out with its centroid at z = +1 mm instead of -1 mm (mirrored), with no word."""
    from ancf_petsc.outline_formats import OutlineReadError
    from ancf_petsc.outline_formats.point_list import read_point_list
    (tmp_path / "o.yaml").write_text("axes: [y, -z]\nunits: um\npoints: [[0, 0], [4, 0], [0, 3]]\n")
    with pytest.raises(OutlineReadError, match=r"o\.yaml holds points \(and a description\) only; its axes, units "
                                               r"would not be read"):
        read_point_list(str(tmp_path / "o.yaml"))
    (tmp_path / "d.yaml").write_text("description: traced 2026\npoints: [[0, 0], [4, 0], [0, 3]]\n")
    assert read_point_list(str(tmp_path / "d.yaml")).points.tolist() == [[0, 0], [4, 0], [0, 3]]


@pytest.mark.parametrize("points,bad", [("[[0, 0], [1, 0], [1, yes], [0, 1]]", "True"),
                                        ("[[0, 0], ['1_0', 0], [1, 1], [0, 1]]", "'1_0'")])
def test_a_yaml_outline_point_that_is_no_number_is_refused(tmp_path, points, bad):
    """A YAML point [1, yes] was read as (1, 1) (YAML's true), ['1_0', 0] as (10, 0), with no word."""
    from ancf_petsc.outline_formats import OutlineReadError
    from ancf_petsc.outline_formats.point_list import read_point_list
    (tmp_path / "o.yaml").write_text(f"points: {points}\n")
    with pytest.raises(OutlineReadError, match=rf"o\.yaml point [23]: {bad} is not a number"):
        read_point_list(str(tmp_path / "o.yaml"))
