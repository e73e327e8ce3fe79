"""Shared pieces of the command line: parser, error handling, output guards."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from geotex.errors import InputError

EXIT_OK = 0
EXIT_NOT_PRINTABLE = 1
EXIT_USAGE = 2
EXIT_INTERNAL = 3


class UsageError(InputError):
    """Bad command-line usage (reported like any other input error)."""


class Parser(argparse.ArgumentParser):
    """An ``ArgumentParser`` whose errors are one line and raise ``UsageError``."""

    def error(self, message):  # noqa: D401 - argparse hook
        raise UsageError(f"{message} (see '{self.prog} --help')")


def flag_error(exc: Exception, flags: dict[str, str]) -> Exception:
    """Rephrase a library error about an option in terms of its CLI flag.

    ``flags`` maps the neutral words the library uses ("tile size") to the
    flag ("--tile-size").  A message starting with one of them ("tile size
    100 is too large...") becomes a :class:`UsageError` naming the flag, and
    "a smaller / larger WORDS" advice names the flag too; other errors are
    returned unchanged.
    """
    message = str(exc)
    hit = False
    for words, flag in flags.items():
        if message.startswith(words + " "):
            message = flag + message[len(words):]
            hit = True
        for size in ("smaller", "larger"):
            if f"a {size} {words}" in message:
                message = message.replace(f"a {size} {words}", f"a {size} {flag}")
                hit = True
    if not hit:
        return exc
    new = UsageError(message)
    new.__cause__ = exc
    return new


MAX_MESSAGE = 600


def fail(message: str, code: int = EXIT_USAGE) -> int:
    """Print ``geotex: error: message`` to stderr and return ``code``.

    The message is kept to one line of at most :data:`MAX_MESSAGE` characters
    (a damaged file can put its own bytes into a parser's message).
    """
    message = " ".join(str(message).split())
    if len(message) > MAX_MESSAGE:
        message = message[:MAX_MESSAGE - 3] + "..."
    print(f"geotex: error: {message}", file=sys.stderr)
    return code


def guard_output(output, *inputs) -> Path:
    """Refuse an output path that is one of the inputs or an existing directory.

    Returns
    -------
    pathlib.Path
        The output path.

    Raises
    ------
    UsageError
        If writing ``output`` would overwrite an input, or its folder is missing.
    """
    out = Path(output)
    for src in inputs:
        if src is None:
            continue
        src = Path(src)
        if out.exists() and src.exists() and os.path.samefile(out, src):
            raise UsageError(f"{out}: refusing to overwrite the input file; "
                             "choose another output name")
        if out.resolve() == src.resolve():
            raise UsageError(f"{out}: refusing to overwrite the input file; "
                             "choose another output name")
    if out.is_dir():
        raise UsageError(f"{out}: is a directory; give an output file name")
    if not out.parent.exists():
        raise UsageError(f"{out}: folder {out.parent} does not exist")
    return out


#: Background loads started by :func:`preload_compiled`; ``main`` waits for them before it returns.
PRELOADS: list = []


def preload_compiled(*, relief: bool = False, three_mf: bool = True) -> None:
    """Start loading the compiled loops of the main job (:func:`geotex.jit.preload`).

    The self-intersection test (input check, shell, union, final check), edge
    topology, degenerate faces, volumes, needle heights and the weld: a fresh
    process otherwise pays for numba (~0.4 s) at the input check, in the main
    thread. ``relief``: also the relief refinement's loops (``geotex displace``);
    otherwise also the tile mapping's (the shaped map's walk to the fitted
    surface, interpolation over the shell's faces). ``three_mf``: also the 3MF
    number-text loops (:mod:`geotex.io.numtext`, six of them, ~0.06 s CPU),
    which only a 3MF file read or written runs.
    """
    import importlib

    from geotex.jit import preload

    modules = ["geotex.check.intersections", "geotex.io", "geotex.mesh.needles"]
    modules += ["geotex.relief.subdivide"] if relief else ["geotex.mapping.shape"]
    for name in modules:
        importlib.import_module(name)
    io = ["geotex.io"] if three_mf else ["geotex.io._common", "geotex.io.stl"]
    packages = ["geotex.check", "geotex.mesh"] + io + (
        ["geotex.relief"] if relief else ["geotex.mapping", "geotex.shells"])
    PRELOADS.append(preload(*packages))
