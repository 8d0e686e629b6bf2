"""The report's tables of an existing run give a fascicle's small displacements in significant
digits: at five decimals of a millimetre a 20 nm move read -0.00002 and a 4 nm one -0.00000."""
from ancf_petsc.paper.run_outputs import mm_cell, probe_markdown


def test_small_probe_displacements_keep_their_digits():
    """A tip that moves 20.46 nm, 8.1 nm and -4.123 nm: before '0.00002 | 0.00001 | -0.00000', now
    to 4 significant digits; at 6.2 mm five decimals as before."""
    summary = {"steps": [{"load_factor": 1.0, "probes": {"tip": {"displacement": [2.046e-8, 8.1e-9, -4.123e-9]}}},
                         {"load_factor": 2.0, "probes": {"tip": {"displacement": [6.20457e-3, 3e-3, -2e-3]}}}]}
    table = probe_markdown(summary, {"probes": [{"name": "tip"}]})
    rows = [[c.strip() for c in line.split("|")[1:-1]] for line in table[-2:]]
    assert rows == [["1", "2.046e-05", "8.1e-06", "-4.123e-06"], ["2", "6.20457", "3.00000", "-2.00000"]]


def test_a_length_cell_is_five_decimals_from_a_hundredth_of_a_millimetre():
    assert (mm_cell(0.0), mm_cell(0.01), mm_cell(-12.345678), mm_cell(0.0063)) == \
        ("0.00000", "0.01000", "-12.34568", "0.0063")
