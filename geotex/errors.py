"""The geotex exception hierarchy.

Every error geotex raises on purpose derives from :class:`GeotexError`.  Errors
caused by a bad argument or a bad input file also derive from ``ValueError`` so
that callers who do not know geotex can still catch them generically.

The command line prints ``geotex: error: <message>`` for any ``GeotexError`` and
exits with status 2, so messages are written to stand alone on one line: they
name the argument or file, the problem, and what to do about it.
"""

from __future__ import annotations

__all__ = [
    "GeotexError",
    "InputError",
    "MeshFileError",
    "MissingFileError",
    "UnsupportedFormatError",
    "NotPrintableError",
    "ExternalToolError",
    "ToolNotFoundError",
    "SolverError",
]


class GeotexError(Exception):
    """Root of every exception geotex raises on purpose."""


class InputError(GeotexError, ValueError):
    """An argument (array, option, file) is invalid."""


class MeshFileError(InputError):
    """A mesh file cannot be read or written: malformed, truncated, wrong type.

    Parameters
    ----------
    path : str or os.PathLike
        The file concerned; it is prefixed to the message.
    message : str
        What is wrong with it.
    """

    def __init__(self, path, message: str):
        self.path = str(path)
        self.reason = message
        super().__init__(f"{self.path}: {message}")


class UnsupportedFormatError(MeshFileError):
    """The file extension (or requested format) is not one geotex handles."""


class MissingFileError(InputError, FileNotFoundError):
    """An input file does not exist or is not a regular file."""


class SolverError(GeotexError):
    """A numerical method failed on valid input: no convergence, a failed factorization.

    Not a ``ValueError``: the arguments passed validation, the algorithm did not
    reach a result.  The message says which method failed and what to change
    (a smaller step, fewer iterations, a finer mesh).
    """


class NotPrintableError(GeotexError):
    """A solid failed the printability check and the caller did not force it.

    Attributes
    ----------
    report : geotex.check.CheckReport
        The full validity report of the refused solid.
    """

    def __init__(self, message: str, report=None):
        self.report = report
        super().__init__(message)


class ExternalToolError(GeotexError):
    """An external program (PrusaSlicer, admesh) failed on a file or timed out.

    Attributes
    ----------
    tool : str
        The program's name.
    """

    def __init__(self, message: str, tool: str = ""):
        self.tool = tool
        super().__init__(message)


class ToolNotFoundError(ExternalToolError):
    """An external program geotex needs is not installed (not on ``PATH``)."""
