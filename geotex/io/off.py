"""OFF (Geomview Object File Format) reading and writing.

Reading
    The header keyword is ``OFF``; ``COFF``, ``NOFF``, ``CNOFF``, ``STOFF``
    and other prefixed variants are accepted and the extra per-vertex columns
    (colours, normals, texture coordinates) ignored.  ``#`` starts a comment
    anywhere.  The counts line ``n_vertices n_faces [n_edges]`` may follow the
    keyword on the same line.  Each vertex is one line ``x y z [extra...]``;
    each face is one line ``k i_1 ... i_k [colour...]`` with 0-based indices.
    Polygons are triangulated without overlaps, concave ones included (see
    :func:`geotex.io._common.triangulate_polygons`); faces with fewer than
    three corners are skipped, counted in ``metadata["skipped_faces"]``.
    Lines after the announced vertices and faces are ignored.  Binary OFF and
    4D / n-dimensional OFF are not supported.

Writing
    ``OFF``, the counts line, vertices with ``repr`` coordinates (exact round
    trip) and ``3 a b c`` faces.
"""

from __future__ import annotations

import re

import numpy as np

from geotex.errors import MeshFileError
from geotex.io._common import (build_mesh, decode_text, first_bad_number, format_rows,
                               line_starts, token_table, triangulate_polygons)

__all__ = ["read_off", "write_off"]

_KEYWORD = re.compile(r"(ST)?(C)?(N)?(4)?(n)?OFF\Z")
_COMMENT = re.compile(r"#[^\n\r]*")


_NONBLANK = re.compile(r"^[ \t\f\v]*\S[^\n]*", re.MULTILINE)


def read_off(path, data: bytes):
    """Parse OFF bytes into a :class:`~geotex.mesh.Mesh` (see module notes).

    Raises
    ------
    MeshFileError
        On a missing ``OFF`` keyword, bad counts, too few lines, malformed
        numbers or non-finite coordinates.
    """
    text = decode_text(path, data, "OFF")
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    if "#" in text:
        text = _COMMENT.sub("", text)
    lines = _NONBLANK.findall(text)

    def line_no(i: int) -> int:
        """1-based file line of non-blank line ``i`` (for error messages)."""
        for j, match in enumerate(_NONBLANK.finditer(text)):
            if j == i:
                return text.count("\n", 0, match.start()) + 1
        return text.count("\n") + 1

    if not lines:
        raise MeshFileError(path, "OFF file has no content (only comments or blanks)")
    head = lines[0].split()
    match = _KEYWORD.match(head[0])
    if match is None:
        raise MeshFileError(path, f"not an OFF file: it must start with 'OFF', found "
                                  f"{head[0][:40]!r}")
    if match.group(4) or match.group(5):
        raise MeshFileError(path, f"{head[0]} (4D / n-dimensional OFF) is not supported")
    rest = head[1:]
    if rest and rest[0].upper() == "BINARY":
        raise MeshFileError(path, "binary OFF is not supported; save it as ASCII OFF")
    cursor = 1
    if not rest:
        if len(lines) < 2:
            raise MeshFileError(path, "OFF file ends before the counts line")
        rest = lines[1].split()
        cursor = 2
    try:
        counts = [int(t) for t in rest[:3]]
    except ValueError:
        counts = []
    if len(counts) < 2 or len(rest) > 3 or min(counts) < 0:
        raise MeshFileError(path, f"bad OFF counts on line {line_no(cursor - 1)}: expected "
                                  f"'n_vertices n_faces n_edges', got {' '.join(rest)[:60]!r}")
    nv, nf = counts[0], counts[1]
    available = len(lines) - cursor
    if nv + nf > available:
        raise MeshFileError(path, f"OFF header announces {nv} vertices and {nf} faces "
                                  f"but the file has only {available} data lines "
                                  "(truncated?)")
    V = _vertices(path, lines[cursor:cursor + nv], lambda i: line_no(cursor + i))
    first_face = cursor + nv
    F, skipped = _faces(path, lines[first_face:first_face + nf], V,
                        lambda i: line_no(first_face + i))
    meta = {"skipped_faces": skipped} if skipped else {}
    return build_mesh(path, V, F, fmt="off", metadata=meta)


def _vertices(path, lines, line_no):
    if not lines:
        return np.zeros((0, 3))
    counts, values, tokens = token_table(lines)
    if (counts < 3).any():
        i = int(np.flatnonzero(counts < 3)[0])
        raise MeshFileError(path, f"OFF line {line_no(i)}: vertex needs x y z, "
                                  f"got {int(counts[i])} values")
    starts = line_starts(counts)
    if values is None:
        picked = [tokens[j] for j in (starts[:, None] + np.arange(3)).ravel().tolist()]
        try:
            return np.array(picked, dtype=np.float64).reshape(-1, 3)
        except ValueError:
            row = next(j // 3 for j, t in enumerate(picked) if first_bad_number([t]) != "?")
            raise MeshFileError(path, f"OFF line {line_no(row)}: bad number "
                                      f"{first_bad_number(picked)!r}") from None
    if (counts == 3).all():
        return values.reshape(-1, 3)
    return values[starts[:, None] + np.arange(3)]


def _faces(path, lines, V, line_no):
    nv = V.shape[0]
    if not lines:
        return np.zeros((0, 3), dtype=np.int64), 0
    counts, values, tokens = token_table(lines)
    starts = line_starts(counts)
    if values is None:
        values = np.full(len(tokens), np.nan)
        for j, t in enumerate(tokens):
            try:
                values[j] = float(t)
            except ValueError:
                pass
    sizes = values[starts]
    bad_size = ~np.isfinite(sizes) | (sizes != np.round(sizes)) | (sizes < 0) | (sizes > 2**40)
    if bad_size.any():
        i = int(np.flatnonzero(bad_size)[0])
        raise MeshFileError(path, f"OFF line {line_no(i)}: bad face size "
                                  f"{tokens[int(starts[i])][:40]!r}")
    sizes = sizes.astype(np.int64)
    short = counts < sizes + 1
    if short.any():
        i = int(np.flatnonzero(short)[0])
        raise MeshFileError(path, f"OFF line {line_no(i)}: face announces "
                                  f"{int(sizes[i])} corners but lists "
                                  f"{int(counts[i]) - 1} values")
    if (sizes == 3).all() and (counts == 4).all():
        flat = values.reshape(-1, 4)[:, 1:].ravel()
    else:
        flat = values[_list_positions(starts + 1, sizes)]
    nonint = ~np.isfinite(flat) | (flat != np.round(flat))
    out = nonint | (flat < 0) | (flat >= nv)
    if out.any():
        corner = int(np.flatnonzero(out)[0])
        face = int(np.searchsorted(np.cumsum(sizes), corner, side="right"))
        token = tokens[int(_list_positions(starts + 1, sizes)[corner])]
        if nonint[corner]:
            msg = f"bad vertex index {token[:40]!r}"
        else:
            msg = f"vertex index {token[:40]} out of range (the file has {nv} vertices)"
        raise MeshFileError(path, f"OFF line {line_no(face)}: {msg}")
    return triangulate_polygons(sizes, flat.astype(np.int64), V)


def _list_positions(first: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """Flat token positions of every list item, given each list's first position."""
    total = int(sizes.sum())
    within = np.arange(total, dtype=np.int64) - np.repeat(line_starts(sizes), sizes)
    return np.repeat(first, sizes) + within


def write_off(fh, mesh, *, path=None, binary: bool = True) -> None:
    """Write ``mesh`` as ASCII OFF to the open binary file ``fh``."""
    V, F = mesh.vertices, mesh.faces
    text = (f"OFF\n{V.shape[0]} {F.shape[0]} 0\n" + format_rows("%r %r %r\n", V)
            + format_rows("3 %d %d %d\n", F))
    fh.write(text.encode("ascii"))
