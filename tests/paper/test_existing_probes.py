"""``ancf-report --existing`` on the paper's model whose probes Table 1 reads are not the paper's:
Table 1 compares probe ``soleus`` (r at the soleus' last node) with the paper's elongations."""
import os
import subprocess

import pytest

from helpers import CONFIGS, MPI_ENV, ROOT, VENV_BIN, load_raw, solve_cli, write_config


@pytest.mark.parametrize("probe, words", [
    ({"name": "soleus", "beam": "soleus", "node": "last", "vector": "mean"},
     "its probe 'soleus' is vector mean at node 8 of soleus, not the paper's vector r at node 8 of soleus, "
     "which Table 1 reads"),
    ({"name": "tip", "beam": "soleus", "node": "last"},
     "it has no probe 'soleus', which Table 1 reads (vector r at node 8 of soleus)")],
    ids=["section mean", "renamed"])
def test_a_paper_run_whose_probes_are_not_the_papers_is_not_compared(tmp_path, probe, words):
    """The paper's tendon (4 elements, psi 45) with its soleus probe the section mean: Table 1 gave
    6.132 mm at 400 N, -0.89 % from the paper, where the paper's quantity (r at the last node) is
    6.205 mm, +0.28 %; with the probe renamed the report ended in a KeyError traceback.  Now such a
    run is reported with its own probe table, not compared, and says why."""
    raw = load_raw("achilles_type3_psi45.yaml")
    for b in raw["beams"]:
        b["section"]["file"] = os.path.join(CONFIGS, b["section"]["file"])
    raw["steps"] = [10.0, 400.0]
    raw["probes"][0] = probe
    raw["output"] = {"vtk": False}
    run = str(tmp_path / "run")
    p = solve_cli(write_config(raw, tmp_path / "c.yaml"), extra=["--output-dir", run, "--quiet"])
    assert p.returncode == 0, p.stderr
    p = subprocess.run([os.path.join(VENV_BIN, "ancf-report"), "--existing", run, "--out", str(tmp_path / "rep")],
                       capture_output=True, text=True, cwd=ROOT, env=dict(os.environ, **MPI_ENV), timeout=300)
    assert p.returncode == 0, p.stderr
    text = open(tmp_path / "rep" / "report.md").read()
    assert "## Table 1" not in text and f"**{run}** is not compared with the paper: {words}." in text
    assert text.splitlines()[0].startswith("# Runs of ")
