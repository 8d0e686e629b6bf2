"""``ancf-report --existing`` on the paper's model whose probes Table 1 reads are not the paper's:
Table 1 compares probe ``soleus`` (r at the soleus' last node) with the paper's elongations."""
import pytest

from helpers import paper_column, report_existing, solved_run


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
    raw = paper_column()
    raw["steps"] = [10.0, 400.0]
    raw["probes"][0] = probe
    raw["output"] = {"vtk": False}
    run = solved_run(raw, tmp_path)
    text = report_existing([run], tmp_path / "rep")
    assert "## Table 1" not in text and f"**{run}** is not compared with the paper: {words}." in text
    assert text.splitlines()[0].startswith("# Runs of ")
