"""Guess a mesh file's format from its content (used to explain failures).

geotex always reads a file as the format its extension (or ``format=``) names
and never silently parses it as something else.  When that fails, the reader
sniffs the content and, if it looks like another supported format, adds a
hint such as ``content looks like a binary STL file; rename it with the .stl
extension`` to the error message.
"""

from __future__ import annotations

import re
import struct

__all__ = ["sniff_format", "describe_format", "mismatch_hint"]

_DESCRIPTIONS = {
    "stl-binary": ("a binary STL file", ".stl"),
    "stl-ascii": ("an ASCII STL file", ".stl"),
    "ply": ("a PLY file", ".ply"),
    "off": ("an OFF file", ".off"),
    "obj": ("an OBJ file", ".obj"),
    "3mf": ("a 3MF file (zip archive)", ".3mf"),
    "glb": ("a GLB (binary glTF) file", ".glb"),
}

_OFF_MAGIC = re.compile(rb"\A\s*(?:#[^\n]*\n\s*)*(?:ST)?C?N?OFF(?:\s|\Z)")
_OBJ_KEYWORDS = {b"v", b"vt", b"vn", b"vp", b"f", b"l", b"p", b"o", b"g", b"s",
                 b"mtllib", b"usemtl"}


def _looks_like_obj(head: bytes) -> bool:
    if b"\x00" in head:
        return False
    lines = head.splitlines()
    if len(head) >= 65536 and lines:
        lines = lines[:-1]          # the last line may be cut in the middle
    seen_vertex = False
    checked = 0
    for raw in lines:
        line = raw.strip()
        if not line or line.startswith(b"#"):
            continue
        keyword = line.split(None, 1)[0]
        if keyword not in _OBJ_KEYWORDS:
            return False
        seen_vertex = seen_vertex or keyword == b"v"
        checked += 1
        if checked >= 200:
            break
    return seen_vertex


def sniff_format(data: bytes, *, size: int | None = None) -> str | None:
    """Return the format the content looks like, or None.

    Parameters
    ----------
    data : bytes
        The whole file, or at least its first 64 KiB (only those are inspected).
    size : int, optional
        The file size, when ``data`` is only its beginning.

    Returns
    -------
    str or None
        One of ``"stl-binary"``, ``"stl-ascii"``, ``"ply"``, ``"off"``,
        ``"obj"``, ``"3mf"``, ``"glb"``.

    Examples
    --------
    >>> sniff_format(b"ply\\nformat ascii 1.0\\n")
    'ply'
    """
    head = data[:65536]
    if head[:4] == b"glTF":
        return "glb"
    if head[:4] == b"PK\x03\x04":
        return "3mf"
    if re.match(rb"ply\r?\n", head):
        return "ply"
    size = len(data) if size is None else size
    if len(head) >= 84:
        (count,) = struct.unpack_from("<I", head, 80)
        if 84 + 50 * count == size:
            return "stl-binary"
    if re.match(rb"\s*solid\b", head, re.IGNORECASE) and b"\x00" not in head:
        return "stl-ascii"
    if _OFF_MAGIC.match(head):
        return "off"
    if _looks_like_obj(head):
        return "obj"
    return None


def describe_format(kind: str) -> tuple[str, str]:
    """Return ``(description, extension)`` for a :func:`sniff_format` result."""
    return _DESCRIPTIONS[kind]


def mismatch_hint(data: bytes, expected: str, *, size: int | None = None) -> str | None:
    """A rename hint when the content looks like a format other than ``expected``.

    Parameters
    ----------
    data : bytes
        File content.
    expected : str
        The format key the file was read as (``"stl"``, ``"obj"``, ...).
    size : int, optional
        The file size, when ``data`` is only its beginning.

    Returns
    -------
    str or None
        ``"content looks like a binary STL file; rename it with the .stl
        extension"``, or None when the content looks like ``expected`` or like
        nothing known.
    """
    kind = sniff_format(data, size=size)
    if kind is None or kind.split("-")[0] == expected:
        return None
    description, ext = describe_format(kind)
    return f"content looks like {description}; rename it with the {ext} extension"
