"""The program's version, with the git commit of the source tree when there is one."""
from __future__ import annotations

import functools
import os

__version__ = "0.1.0"


@functools.lru_cache(maxsize=1)
def git_describe() -> str | None:
    """``<short hash>`` (``-dirty`` when the tree has changes) of the checkout this package runs
    from, or None outside a git checkout (an installed wheel, a tarball) or without git."""
    here = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    if not os.path.exists(os.path.join(here, ".git")):
        return None
    import subprocess                      # here only: not every import of the package runs git
    try:
        out = subprocess.run(["git", "-C", here, "describe", "--always", "--dirty", "--abbrev=10",
                              "--match", "NO-TAGS-ONLY-HASH"], capture_output=True, text=True,
                             timeout=10, stdin=subprocess.DEVNULL)
    except (OSError, subprocess.SubprocessError):
        return None
    text = out.stdout.strip()
    return text if out.returncode == 0 and text else None


def version_info() -> dict:
    """``{"version": "0.1.0", "git": "abc1234567" | None}`` (stored in results.h5 and summary.json)."""
    return {"version": __version__, "git": git_describe()}


def version_line(prog: str = "ancf-solve") -> str:
    info = version_info()
    git = f" (git {info['git']})" if info["git"] else ""
    return f"{prog} {info['version']}{git}"
