"""File-system helpers shared by the writers (results, sweeps, studies): atomic replacement, the
output directory check, and OS errors turned into one-line ``OutputError``s."""
from __future__ import annotations

import errno
import json
import os
import socket
import threading
import time

import numpy as np

from ..errors import OutputError  # noqa: F401  (raised here; its home is errors.py, the API's)

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


def _dangling_link(path: str) -> str | None:
    """``path`` or the first of its parents that is a symbolic link to nothing, else None."""
    parts = os.path.normpath(path).split(os.sep)
    for k in range(1, len(parts) + 1):
        head = os.sep.join(parts[:k]) or os.sep
        if os.path.islink(head) and not os.path.exists(head):
            return head
        if not os.path.lexists(head):
            return None
    return None


def prepare_output_dir(path: str, keys: str = "output.dir / --output-dir") -> None:
    """Create ``path`` if needed and check that files can be written in it (rank 0 only);
    raises ``OutputError`` naming the path, the reason and the ``keys`` that choose it."""
    if not path:
        raise OutputError("''", f"the output directory is an empty path (give {keys} a directory)")
    if os.path.realpath(path) == os.path.realpath(os.sep):
        raise OutputError(path, "is the root directory: give the results a directory of their "
                                f"own ({keys})")
    dangling = _dangling_link(path)
    if dangling:
        raise OutputError(dangling, f"is a dangling symbolic link (to {os.readlink(dangling)}): "
                                    f"create its target or choose another {keys}")
    if os.path.exists(path) and not os.path.isdir(path):
        raise OutputError(path, f"exists and is not a directory (choose another {keys})")
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


#: the lock file that marks an output directory in use by a run
LOCK_NAME = ".ancf-lock"


def _proc_stat(pid: int) -> list[str] | None:
    """/proc/<pid>/stat after the command name (state first), or None."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None


def _process_start(pid: int) -> str | None:
    """The start time of process ``pid`` (clock ticks since boot), or None."""
    stat = _proc_stat(pid)
    return stat[19] if stat and len(stat) > 19 else None


def _alive(pid: int, start: str | None) -> bool:
    """Whether ``pid`` still runs and is the process that wrote the lock (same start time; a
    killed process not yet reaped, a zombie, has ended)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    stat = _proc_stat(pid)
    if stat and stat[0] in ("Z", "X"):
        return False
    now = _process_start(pid)
    return start is None or now is None or now == start


class DirectoryLock:
    """An output directory's lock (rank 0): created exclusively with the holder's pid, host and
    start, removed by ``release``.  A lock whose process is gone (same host) is stale and taken
    over; ``stale`` then describes the one removed."""

    def __init__(self, directory: str):
        self.path = os.path.join(directory, LOCK_NAME)
        self.stale: str | None = None
        self.held = False

    def acquire(self) -> None:
        """Take the lock or raise OutputError naming the run that holds it."""
        me = {"pid": os.getpid(), "host": socket.gethostname(), "start": _process_start(os.getpid()),
              "since": time.strftime("%Y-%m-%d %H:%M:%S")}
        for _ in range(2):
            try:
                fd = os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
            except FileExistsError:
                holder = self._holder()
                if not self._live(holder):
                    self.stale = ("a stale lock" if holder is None else
                                  f"the stale lock of pid {holder.get('pid')} (since {holder.get('since')}, "
                                  "no longer running)")
                    remove_quietly(self.path)
                    continue
                raise OutputError(os.path.dirname(self.path) or ".",
                                  f"in use by another run (pid {holder.get('pid')} on {holder.get('host')}, "
                                  f"since {holder.get('since')}); choose another output directory, or "
                                  f"remove {self.path} if that run is gone") from None
            except OSError as exc:
                raise OutputError(self.path, f"cannot create the lock file: {os_reason(exc)}") from None
            with os.fdopen(fd, "w") as fh:
                json.dump(me, fh)
            self.held = True
            return
        raise OutputError(self.path, "could not take the lock (another run took it meanwhile)")

    def live_holder(self) -> dict | None:
        """The run that holds the lock (pid, host, since), or None: no lock, or a stale one."""
        holder = self._holder()
        return holder if self._live(holder) else None

    @staticmethod
    def _live(holder: dict | None) -> bool:
        """A lock's holder runs: on this host its process is alive; another host's is taken as running."""
        return holder is not None and (holder.get("host") != socket.gethostname()
                                       or _alive(int(holder.get("pid", -1)), holder.get("start")))

    def _holder(self) -> dict | None:
        try:
            with open(self.path) as fh:
                return json.load(fh)
        except (OSError, ValueError):
            return None

    def release(self) -> None:
        """Remove the lock if this process holds it."""
        if self.held:
            holder = self._holder()
            if holder is not None and holder.get("pid") == os.getpid():
                remove_quietly(self.path)
            self.held = False


def plain(obj):
    """Config data → plain Python types (numpy scalars/arrays become floats/lists)."""
    if isinstance(obj, dict):
        return {str(k): plain(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [plain(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return plain(obj.tolist())
    if isinstance(obj, np.generic):
        return obj.item()
    return obj
