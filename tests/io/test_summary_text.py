"""summary.json's text during a run is json.dumps's, byte for byte, with each level encoded once."""
import json
import math

from ancf_petsc.io.results import compact_summary


def _summary(n):
    return {"name": "x", "status": "running", "warnings": ["a \"quoted\" note", "ü"],
            "steps": [{"load_factor": k / 7, "probes": {"p": {"value": [k, -0.5, 1e-300]}},
                       "residual_norm": math.nan if k == 2 else 1e-9 * k, "newton_history": [[1, 2.5]]}
                      for k in range(n)],
            "last_converged": {"step": n}}


def test_compact_summary_is_json_dumps_at_every_level_and_after_a_restart():
    s, cache = _summary(0), []
    for k in range(6):
        assert compact_summary(s, cache) == json.dumps(s, separators=(",", ":"))
        s["steps"].append(_summary(k + 1)["steps"][k])
        s["updated"] = f"t{k}"
    assert len(cache) == 5
    s["steps"] = s["steps"][:3]                          # a restart cuts the levels
    assert compact_summary(s, cache) == json.dumps(s, separators=(",", ":"))
    s["steps"] = [dict(e) for e in s["steps"]]           # … or replaces them
    s["steps"][0]["load_factor"] = 9.0
    assert compact_summary(s, cache) == json.dumps(s, separators=(",", ":"))
    assert json.loads(compact_summary(s, cache))["steps"][0]["load_factor"] == 9.0
