"""Errors a user can fix.  ``InputError(path, message)`` names the config key path it is about.

Lower layers (physics, contact) raise it with the key path they know; the command-line programs
print it as one line and exit with code 2.  ``config.ConfigError`` is the same class.
"""
from __future__ import annotations


class InputError(Exception):
    """A problem with the input: ``path`` is the key path (e.g. ``beams[0].material.mu``)."""

    def __init__(self, path: str, message: str):
        super().__init__(f"{path}: {message}" if path else message)
        self.path = path
