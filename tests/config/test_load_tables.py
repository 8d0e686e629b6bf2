"""The load tables of a history (config/load_tables.py) in the forms real exports take: OpenSim
storage files and CSV files with a separator ending every line, rows written with spaces under a
tab-separated header; what stays refused names the file, row and column and what to do."""
import numpy as np
import pytest

from ancf_petsc.config.load_tables import read_load_table
from ancf_petsc.config.values import ConfigError

HEADER = "name\nversion=1\nnRows=2\nnColumns=3\ninDegrees=yes\nendheader\n"
FRAMES = {"time": [0.25, 0.27], "soleus_r": [9.5, 120.0], "gasmed_r": [8.0, 95.5]}


def _read(tmp_path, name: str, text: str, newline: str = "\n"):
    path = tmp_path / name
    path.write_bytes(text.replace("\n", newline).encode())
    return read_load_table(str(path), "history.file")


@pytest.mark.parametrize("name,text", [
    ("tab_each.sto", HEADER + "time\tsoleus_r\tgasmed_r\t\n0.25\t9.5\t8\t\n0.27\t120\t95.5\t\n"),
    ("tab_each.mot", HEADER + "time\tsoleus_r\tgasmed_r\t\n0.25\t9.5\t8\t\n0.27\t120\t95.5\t\n\n"),
    ("comma_each.csv", "time,soleus_r,gasmed_r,\n0.25,9.5,8,\n0.27,120,95.5,\n"),
    ("excel.csv", "time,soleus_r,gasmed_r,,\n0.25,9.5,8,,\n0.27,120,95.5,,\n,,,,\n"),
], ids=lambda v: v if "." in v and "\n" not in v else "")
@pytest.mark.parametrize("newline", ["\n", "\r\n"], ids=["lf", "crlf"])
def test_a_separator_ending_every_line_is_no_column(tmp_path, name, text, newline):
    """A tab after each value of an OpenSim file was refused 'its header says nColumns=3, the
    table has 4 columns: a file cut short?', a CSV file's trailing comma 'column 4 of the header
    line has no name'; both are read as the frames written."""
    table = _read(tmp_path, name, text, newline)
    assert list(table.columns) == list(FRAMES)
    for k, v in FRAMES.items():
        assert np.array_equal(table.columns[k], v)


def test_rows_written_with_spaces_under_a_tab_separated_header(tmp_path):
    """A hand-edited storage file whose header is tab-separated and rows space-separated was
    refused 'data row 1 (line 8) has 1 fields, the header 3'."""
    table = _read(tmp_path, "mixed.sto", HEADER + "time\tsoleus_r\tgasmed_r\n0.25  9.5  8\n0.27 120 95.5\n")
    for k, v in FRAMES.items():
        assert np.array_equal(table.columns[k], v)


@pytest.mark.parametrize("name,text,match", [
    ("missing.sto", HEADER + "time\tsoleus_r\tgasmed_r\t\n0.25\t9.5\t\t\n0.27\t120\t95.5\t\n",
     r"missing\.sto: data row 1 \(line 8\), column 'gasmed_r': '' is not a finite number"),
    ("wide.sto", HEADER + "time\tsoleus_r\tgasmed_r\ttibpost_r\n0.25\t9.5\t8\t1\n0.27\t120\t95.5\t1\n",
     r"wide\.sto: its header says nColumns=3, the table has 4 columns: more than it states: correct nColumns"),
    ("unnamed.csv", "time,,gasmed_r\n0.25,9.5,8\n0.27,120,95.5\n",
     r"unnamed\.csv: column 2 of the header line has no name: name it, or remove the column"),
], ids=["missing", "wide", "unnamed"])
def test_what_stays_refused_says_where_and_what_to_do(tmp_path, name, text, match):
    with pytest.raises(ConfigError, match=match):
        _read(tmp_path, name, text)


def test_an_inline_table_reads_numbers_as_steps_do():
    """PyYAML reads 1e3 and 1e-2 (no '.') as strings: steps, forces and curves take them as
    numbers, a history table refused them ('history.table.soleus[0]: expected a finite number;
    got '1e3''). The same frames written either way are the same table."""
    from ancf_petsc import yamlio
    from ancf_petsc.config.load_tables import inline_table
    table = yamlio.load("{time: [0, 1e-2], soleus: [1e3, 2.5e3]}")
    got = inline_table(table, "history.table")
    assert np.array_equal(got.columns["time"], [0.0, 0.01])
    assert np.array_equal(got.columns["soleus"], [1000.0, 2500.0])
    for bad, match in (("[1, nan]", r"history\.table\.soleus\[1\]: must be a finite number; got nan"),
                       ("[1, ten]", r"history\.table\.soleus\[1\]: expected a number; got 'ten'"),
                       ("[1, true]", r"history\.table\.soleus\[1\]: expected a number; got True"),
                       # quoted, '1_0' is a string float() reads as 10: refused as in a CSV cell
                       ("[1, '1_0']", r"history\.table\.soleus\[1\]: expected a number; got '1_0'")):
        with pytest.raises(ConfigError, match=match):
            inline_table(yamlio.load(f"{{time: [0, 1], soleus: {bad}}}"), "history.table")


@pytest.mark.parametrize("data,match", [
    ("time,soleus_r\n0,1\n0.1,2\n".encode("utf-16"), r"byte 0xff in line 1, UTF-16: Excel Unicode text\): save it as UTF-8"),
    ("# Kraft in N, 20 \u00b0C\ntime,soleus_r\n0,1\n".encode("cp1252"), r"byte 0xb0 in line 1\): save it as UTF-8"),
], ids=["utf16", "cp1252"])
def test_a_table_not_in_utf8_says_where_and_how_to_save_it(tmp_path, data, match):
    """'cannot read it as UTF-8 text (UnicodeDecodeError)' said neither where nor what to do."""
    (tmp_path / "t.csv").write_bytes(data)
    with pytest.raises(ConfigError, match=r"^history\.file: .*t\.csv: not UTF-8 text \(" + match):
        read_load_table(str(tmp_path / "t.csv"), "history.file")


@pytest.mark.parametrize("name,text,match", [
    ("words.sto", HEADER.replace("nRows=2", "nRows=three") + "time\tsoleus_r\tgasmed_r\n0.25\t9.5\t8\n",
     r"words\.sto: header line 3 'nRows=three' is not a count of data rows: write it as a whole "
     r"number \(nRows=1 for this table\)"),
    ("blank.sto", HEADER.replace("nColumns=3", "nColumns=") + "time\tsoleus_r\tgasmed_r\n0.25\t9.5\t8\n0.27\t1\t2\n",
     r"blank\.sto: header line 4 'nColumns=' is not a count of columns"),
    ("underscore.csv", "time,soleus_r\n0,1_0\n0.1,2\n",
     r"underscore\.csv: data row 1 \(line 2\), column 'soleus_r': '1_0' is not a finite number"),
], ids=["nrows-words", "ncolumns-empty", "underscore"])
def test_a_header_size_or_a_cell_that_is_no_number_is_refused(tmp_path, name, text, match):
    """nRows=three skipped the size check, so a file cut short was read as a shorter history;
    a cell 1_0 was read as 10 (Python's float() takes underscores between digits)."""
    with pytest.raises(ConfigError, match=r"^history\.file: .*" + match):
        _read(tmp_path, name, text)



@pytest.mark.parametrize("raw,path", [
    ({"table": {"time": [0, 1], "1": [5, 6]}, "time": "time"}, None),
    ({"table": {"1": [0, 1], "f": [5, 6]}, "time": 1}, "history.time"),
])
def test_a_column_named_by_a_yaml_number_says_to_quote_it(tmp_path, raw, path):
    """column: 1 (YAML's int) failed 'expected a non-empty string; got 1', with no word of quoting."""
    from ancf_petsc.config.history import history_curve, parse_history
    if path is not None:
        with pytest.raises(ConfigError, match=r"^history\.time: expected a column name; got the number 1: "
                                              r"a column named by digits is quoted in YAML \(column: \"1\"\)"):
            parse_history(raw, str(tmp_path))
        return
    history = parse_history(raw, str(tmp_path))
    with pytest.raises(ConfigError, match=r"^loads\[0\]\.column: expected a column name; got the number 1: "
                                          r"a column named by digits is quoted in YAML \(column: \"1\"\)"):
        history_curve({"column": 1}, history, "loads[0]", None)
    assert history_curve({"column": "1"}, history, "loads[0]", None) == ((0.0, 0.0), (1.0, 5.0), (2.0, 6.0))


@pytest.mark.parametrize("name,text,line", [
    ("nohead.csv", "0,9.1\n0.01,9.2\n0.02,50\n", 1),
    ("nohead.sto", HEADER.replace("nRows=2", "nRows=1") + "0\t9.5\t8\n0.27\t120\t95.5\n", 7),
], ids=["csv", "sto"])
def test_a_table_without_a_header_line_is_refused(tmp_path, name, text, line):
    """A CSV file of numbers only was read with its first frame as column names: the error then
    said 'no column 'time' (columns: 0, 9.1); name the clock column', and history.time: "0" with
    column: "9.1" ran the other frames, 'completed', the first frame (t = 0, 9.1 N) lost."""
    with pytest.raises(ConfigError, match=rf"^history\.file: .*{name}: its header line \(line {line}\) "
                                          r"'0,9\.\d+,?\d*' is numbers, not column names: .* add a line naming"):
        _read(tmp_path, name, text)
