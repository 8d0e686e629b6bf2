"""The documentation: a short README that reaches every page, links that resolve, and the
config reference in step with the code's defaults (issue 14)."""
import os
import re

import pytest

from helpers import ROOT

README = os.path.join(ROOT, "README.md")
DOCS = os.path.join(ROOT, "docs")
LINK = re.compile(r"\]\(([^)#\s]+)(#[^)\s]*)?\)")


def _pages():
    return sorted(os.path.join(DOCS, f) for f in os.listdir(DOCS) if f.endswith(".md"))


def _links(path):
    with open(path, encoding="utf-8") as fh:
        text = fh.read()
    base = os.path.dirname(path)
    out = []
    for target, _ in LINK.findall(text):
        if re.match(r"[a-z]+://", target):
            continue
        out.append(os.path.relpath(os.path.normpath(os.path.join(base, target)), ROOT))
    return out


def test_readme_is_short():
    with open(README, encoding="utf-8") as fh:
        assert len(fh.readlines()) < 400


def test_every_docs_page_is_linked_from_the_readme():
    linked = set(_links(README))
    for page in _pages():
        assert os.path.relpath(page, ROOT) in linked, f"{page} is not reachable from README.md"


@pytest.mark.parametrize("path", [README] + _pages(), ids=lambda p: os.path.relpath(p, ROOT))
def test_relative_links_resolve(path):
    missing = [t for t in _links(path) if not os.path.exists(os.path.join(ROOT, t))]
    assert not missing, f"{os.path.relpath(path, ROOT)}: broken links {missing}"


def test_config_reference_shows_the_default_axial_rule():
    from ancf_petsc.config.specs import BeamSpec, DEFAULT_AXIAL_POINTS
    with open(README, encoding="utf-8") as fh:
        text = fh.read()
    assert re.search(rf"^\s+axial_points: {DEFAULT_AXIAL_POINTS}\s+# Gauss points along xi", text, re.M)
    assert BeamSpec.__dataclass_fields__["axial_points"].default == DEFAULT_AXIAL_POINTS


def test_readme_python_api_example_runs(tmp_path):
    """The README's Python example, run as written (from a copy of the repository's configs, in
    a fresh process: ``import ancf_petsc`` initialises nothing until ``solve``)."""
    import shutil
    import subprocess
    import sys

    from helpers import MPI_ENV
    with open(README, encoding="utf-8") as fh:
        text = fh.read()
    code = re.search(r"\*\*Python API\.\*\*.*?```python\n(.*?)```", text, re.S).group(1)
    shutil.copytree(os.path.join(ROOT, "configs"), tmp_path / "configs")
    p = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True,
                       timeout=300, env=dict(os.environ, **MPI_ENV, PYTHONPATH=ROOT))
    assert p.returncode == 0, p.stdout + p.stderr
    first, second = p.stdout.splitlines()
    assert first == "completed 0"
    level, disp = second.split(" ", 1)
    assert float(level) == 1.0 and disp.startswith("[") and float(disp.strip("[]").split()[0]) > 0.0
