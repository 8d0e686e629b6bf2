"""Errors a user can fix.  ``InputError(path, message, kind)`` names the config key path it is about.

Lower layers (physics, contact) raise it with the key path they know; the command-line programs
print it as one line and exit with code 2.  ``config.ConfigError`` is the same class.  Callers
read ``path``, ``message`` and ``kind`` (one of ``KINDS``), never the text of ``str(exc)``.
``OutputError(path, reason)``: the output (a file or directory ``path``) cannot be written.
"""
from __future__ import annotations

__all__ = ["InputError", "INVALID", "KINDS", "MISSING_KEY", "OutputError", "UNKNOWN_KEY"]

#: kinds of input error: a value that is wrong, a key the format does not know, a required key
#: left out
INVALID = "invalid"
UNKNOWN_KEY = "unknown_key"
MISSING_KEY = "missing_key"
KINDS = (INVALID, UNKNOWN_KEY, MISSING_KEY)


class InputError(Exception):
    """A problem with the input: ``path`` is the key path (e.g. ``beams[0].material.mu``),
    ``message`` what is wrong there and the fix, ``kind`` one of ``KINDS``."""

    def __init__(self, path: str, message: str, kind: str = INVALID):
        if kind not in KINDS:
            raise ValueError(f"InputError kind {kind!r} is not one of {KINDS}")
        super().__init__(f"{path}: {message}" if path else message)
        self.path, self.message, self.kind = path, message, kind


class OutputError(Exception):
    """A file-system problem with the output; ``path`` is the file or directory concerned."""

    def __init__(self, path: str, reason: str):
        super().__init__(f"{path}: {reason}")
        self.path, self.reason = path, reason
