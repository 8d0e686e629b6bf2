"""PETSc options read from files and the environment, checked like the command line's.

PETSc reads options from ``-options_file FILE`` (also inside such a file), from the
``PETSC_OPTIONS`` environment variable and from ``~/.petscrc``, ``./.petscrc`` and ``./petscrc``
(unless ``-skip_petscrc``).  A file PETSc cannot open or parse stops ``PetscInitialize`` with a
banner and a traceback, and a bad value inside one surfaces only when a solver reads it, blamed
on the solver.  ``check_all_options`` reads them the way PETSc 3.18's
``PetscOptionsInsertFilePetsc`` does (one option per line: ``-name [value]``, ``alias -new -old``,
``#`` starts a comment; tabs and carriage returns are blanks; a third token is an error) and
returns the first problem as one line naming the file, its line and the option, before PETSc
starts.  Pure Python: runs before PETSc is initialised.
"""
from __future__ import annotations

import os

from ..linalg.option_syntax import check_value, command_line_options, stray_words

#: options whose value is a file of options (``-options_file_yaml``: only checked for existence)
FILE_OPTIONS = ("options_file", "options_file_yaml")
#: rc files PETSc reads from the home and the working directory
RC_FILES = ("~/.petscrc", ".petscrc", "petscrc")
_MAX_DEPTH = 10


class OptionsFileError(Exception):
    """One line: which file (and line) PETSc could not use, and why."""


def _tokens(line: str) -> list[str]:
    """PETSc's tokens of one line: blanks separate, a double-quoted token keeps its blanks."""
    line = line.split("#", 1)[0].replace("\t", " ").replace("\r", " ")
    out, rest = [], line.strip()
    while rest:
        if rest.startswith('"') and '"' in rest[1:]:
            end = rest.index('"', 1)
            out.append(rest[1:end])
            rest = rest[end + 1:].lstrip()
        else:
            tok, _, rest = rest.partition(" ")
            out.append(tok)
            rest = rest.lstrip()
    return out


def _valid_key(token: str) -> bool:
    """PetscOptionsValidKey: a dash (or two) and a letter."""
    t = token[1:] if token.startswith("--") else token
    return t.startswith("-") and len(t) > 1 and t[1].isalpha()


def _read(path: str) -> str:
    """The text of an options file, or OptionsFileError saying why it cannot be read."""
    where = f"-options_file {path}"
    if not os.path.lexists(path):
        raise OptionsFileError(f"{where}: no such file (give the path of a text file of PETSc "
                               "options, one '-name value' per line)")
    if not os.path.exists(path):
        raise OptionsFileError(f"{where}: a dangling symbolic link (to {os.readlink(path)})")
    if os.path.isdir(path):
        raise OptionsFileError(f"{where}: is a directory, not a file of PETSc options")
    try:
        with open(path, "rb") as fh:
            data = fh.read(1 << 20)
    except OSError as exc:
        raise OptionsFileError(f"{where}: cannot be read ({exc.strerror})") from None
    if b"\0" in data:
        raise OptionsFileError(f"{where}: is a binary file, not a text file of PETSc options")
    return data.decode("utf-8", errors="replace")


def file_options(path: str, depth: int = 0) -> list[tuple[str, str | None, str]]:
    """(name without the dash, value or None, 'FILE line N') of every option in an options file,
    nested ``-options_file`` included; OptionsFileError where PETSc would stop."""
    if depth > _MAX_DEPTH:
        raise OptionsFileError(f"-options_file {path}: -options_file nested more than "
                               f"{_MAX_DEPTH} deep (does a file include itself?)")
    aliases: dict[str, str] = {}
    out = []
    for n, line in enumerate(_read(path).splitlines(), start=1):
        where = f"{path} line {n}"
        toks = _tokens(line)
        if not toks:
            continue
        if toks[0] == "alias":
            if len(toks) != 3 or not (_valid_key(toks[1]) and _valid_key(toks[2])):
                raise OptionsFileError(f"options file {where}: write an alias as "
                                       "'alias -new_name -petsc_option'")
            aliases[toks[1].lstrip("-")] = toks[2].lstrip("-")
            continue
        if not _valid_key(toks[0]):
            raise OptionsFileError(f"options file {where}: {toks[0]!r} is not an option; each "
                                   "line holds one option, '-name [value]' (comments start with #)")
        if len(toks) > 2:
            raise OptionsFileError(f"options file {where}: {toks[2]!r} after '{toks[0]} {toks[1]}': "
                                   "one option per line")
        name = toks[0].lstrip("-")
        name = aliases.get(name, name)
        value = toks[1] if len(toks) > 1 else None
        out.append((name, value, where))
        if name in FILE_OPTIONS:
            out += _nested(name, value, where, depth)
    return out


def _nested(name: str, value: str | None, where: str, depth: int) -> list:
    """The options of the file a ``-options_file`` names (``-options_file_yaml``: it must exist)."""
    if value is None:
        raise OptionsFileError(f"-{name} ({where}): needs the path of a file")
    if name == "options_file_yaml":
        _read(value)
        return []
    return file_options(value, depth + 1)


def all_options(args: list[str], environ=None) -> list[tuple[str, str | None, str]]:
    """(name, value, source) of the options PETSc will read: command line, ``-options_file``
    files, ``PETSC_OPTIONS`` and the rc files; OptionsFileError where PETSc would stop."""
    environ = os.environ if environ is None else environ
    out = [(name, value, "") for name, value in command_line_options(args)]
    env = environ.get("PETSC_OPTIONS", "")
    out += [(name, value, "PETSC_OPTIONS") for name, value in command_line_options(env.split())]
    if not any(name == "skip_petscrc" for name, _, _ in out):
        for rc in RC_FILES:
            path = os.path.expanduser(rc)
            if os.path.isfile(path):
                out += file_options(path)
    for name, value, where in list(out):
        if name in FILE_OPTIONS and where in ("", "PETSC_OPTIONS"):   # files' own are read already
            out += _nested(name, value, where or "command line", 0)
    return out


def check_all_options(args: list[str], own: tuple[str, ...] = (), environ=None) -> str | None:
    """The first option PETSc would refuse or that is not PETSc's, as one line, or None.

    ``own``: the program's own options (``--restart``): written with one dash in a file they
    would go to PETSc, so they are refused there too."""
    stray = stray_words(args)
    if stray:
        return (f"{stray[0]}: neither an option nor an option's value on the command line (PETSc would "
                "skip it); give one input file, and PETSc options with one dash and at most one value "
                "each, e.g. -snes_max_it 30")
    try:
        options = all_options(args, environ)
    except OptionsFileError as exc:
        return str(exc)
    for name, value, where in options:
        source = f" ({where})" if where else ""
        shown = f"-{name}" + (f" {value}" if value is not None else "")
        if "=" in name:                   # PETSc reads an option named 'snes_max_it=3' and never uses it
            key, _, given = name.partition("=")
            return (f"PETSc option {shown}{source}: PETSc takes an option's value after a space, not '=': "
                    f"write -{key} {given}")
        if "--" + name.replace("_", "-") in own and where:
            return (f"{shown}{source}: ancf-solve's own options go on the command line with two "
                    f"dashes (--{name.replace('_', '-')}), not in PETSc's options")
        why = check_value(name, value)
        if why:
            return f"PETSc option {shown}{source}: {why}"
    return None
