"""File-system helpers shared by the writers (results, sweeps, studies): atomic replacement, the
output directory check, and OS errors turned into one-line ``OutputError``s."""
from __future__ import annotations

import errno
import os
import threading

#: errno values that mean the disk (or quota) is full
NO_SPACE = (errno.ENOSPC, errno.EDQUOT, errno.EFBIG)


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


class OutputError(Exception):
    """A file-system problem with the output; ``path`` is the file or directory concerned."""

    def __init__(self, path: str, reason: str):
        super().__init__(f"{path}: {reason}")
        self.path, self.reason = path, reason


def os_reason(exc: BaseException) -> str:
    """The OS's words for an error (``No space left on device``), h5py's otherwise."""
    err = getattr(exc, "errno", None)
    if err:
        return os.strerror(err)
    text = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
    for code in NO_SPACE:                       # h5py: "... errno = 28, error message = ..."
        if f"errno = {code}," in str(exc):
            return os.strerror(code)
    return text


def remove_quietly(*paths: str) -> None:
    for p in paths:
        try:
            os.remove(p)
        except OSError:
            pass


def prepare_output_dir(path: str) -> None:
    """Create ``path`` if needed and check that files can be written in it (rank 0 only);
    raises ``OutputError`` naming the path and the reason."""
    if os.path.exists(path) and not os.path.isdir(path):
        raise OutputError(path, "exists and is not a directory (choose another output.dir / --output-dir)")
    try:
        os.makedirs(path, exist_ok=True)
    except OSError as exc:
        where = exc.filename or path
        if isinstance(exc, (FileExistsError, NotADirectoryError)):
            raise OutputError(where, "cannot create the output directory: a file is in the way") from None
        raise OutputError(where, f"cannot create the output directory: {os_reason(exc)}") from None
    probe = os.path.join(path, f".ancf-write-test-{os.getpid()}")
    try:
        with open(probe, "w") as fh:
            fh.write("ok")
    except OSError as exc:
        remove_quietly(probe)
        raise OutputError(path, f"cannot write in the output directory: {os_reason(exc)}") from None
    remove_quietly(probe)
