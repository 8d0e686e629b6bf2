"""Small file-system helpers shared by the writers (results, sweeps, studies)."""
from __future__ import annotations

import os
import threading


def atomic_write(path: str, text: str) -> None:
    """Replace ``path`` by ``text`` atomically (a temporary file beside it, then rename), so a
    reader never sees half a file; the temporary file is removed if writing fails."""
    tmp = f"{path}.tmp{os.getpid()}.{threading.get_ident()}"
    try:
        with open(tmp, "w") as fh:
            fh.write(text)
        os.replace(tmp, path)
    except OSError:
        try:
            os.remove(tmp)
        except OSError:
            pass
        raise
