"""Helpers shared by the format modules: welding, polygons, validation, text."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from geotex.errors import InputError, MeshFileError
from geotex.jit import JIT_MIN_SIZE, compiled
from geotex.mesh.polygons import polygon_triangle_corners
from geotex.mesh.record import Mesh

__all__ = [
    "weld_exact", "fan_triangulate", "triangulate_polygons", "build_mesh", "check_finite", "decode_text",
    "format_rows", "first_bad_number", "per_vertex_uv", "tokens_per_line",
    "token_table", "line_starts", "gc_paused",
]

_MIX1 = np.uint64(0x9E3779B97F4A7C15)
_MIX2 = np.uint64(0xC2B2AE3D27D4EB4F)
_MIX3 = np.uint64(0x165667B19E3779F9)


def _exact_columns(P: np.ndarray) -> list[np.ndarray]:
    """1-D unsigned integer columns whose tuple identifies each row's bit pattern."""
    if P.dtype.itemsize == 4:
        B = P.view(np.uint32).reshape(P.shape)
        xy = B[:, 0].astype(np.uint64)
        xy <<= np.uint64(32)
        xy |= B[:, 1]
        return [xy, B[:, 2].astype(np.uint64)]
    B = P.view(np.uint64).reshape(P.shape)
    return [np.ascontiguousarray(B[:, j]) for j in range(3)]


def _hash_columns(columns: list[np.ndarray]) -> np.ndarray:
    """A 64-bit mixing hash of the columns (collisions possible, checked later)."""
    key = columns[0] * _MIX1
    for col, mix in zip(columns[1:], (_MIX2, _MIX3)):
        high = key >> np.uint64(35)             # rotate left by 29, in place
        key <<= np.uint64(29)
        key |= high
        del high
        key ^= col * mix
    return key


def weld_exact(P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge rows of ``P`` with exactly equal coordinates.

    ``-0.0`` and ``0.0`` are equal (they compare equal) and weld; rows must be
    finite (check first).  Rows are grouped by sorting a 64-bit hash of their
    bit patterns; the groups are then verified exactly, with a lexicographic
    sort as the fallback should two different rows share a hash.

    Parameters
    ----------
    P : numpy.ndarray, (k, 3) float32 or float64
        Corner positions.

    Returns
    -------
    unique : numpy.ndarray, (n, 3) same dtype as ``P``
        Distinct rows ordered by their first appearance in ``P``.
    inverse : numpy.ndarray, (k,) int64
        ``unique[inverse] == P``.
    """
    k = P.shape[0]
    if k == 0:
        return P.reshape(0, 3).copy(), np.zeros(0, dtype=np.int64)
    Q = np.ascontiguousarray(P)
    if np.may_share_memory(Q, P):
        Q = Q + Q.dtype.type(0.0)      # -0.0 + 0.0 == +0.0: one bit pattern for zero
    else:
        Q += Q.dtype.type(0.0)         # a copy already: no second one
    P = Q
    del Q
    columns = _exact_columns(P)
    key = _hash_columns(columns)
    if k >= JIT_MIN_SIZE:
        bits = max(4, int(2 * k - 1).bit_length())
        # row ids as int32 when they fit (the table is the largest array here)
        rows = np.int32 if k < 2 ** 31 else np.int64
        table = np.full(1 << bits, -1, dtype=rows)
        inverse = np.empty(k, dtype=np.int64)
        first = np.empty(k, dtype=rows)
        extra = columns[2] if len(columns) == 3 else columns[1][:0]
        n = _weld_table(key, columns[0], columns[1], extra, table, 64 - bits, inverse, first)
        del table, key, columns, extra
        return P[first[:n]], inverse
    perm = np.argsort(key, kind="quicksort")
    ks = key[perm]
    boundary = np.empty(k, dtype=bool)
    boundary[0] = True
    np.not_equal(ks[1:], ks[:-1], out=boundary[1:])
    del ks, key
    # Inside a hash group every row must equal its neighbour; otherwise two
    # different rows share a hash (astronomically rare): sort exactly instead.
    same = ~boundary[1:]
    for col in columns:
        cs = col[perm]
        if ((cs[1:] != cs[:-1]) & same).any():
            perm = np.lexsort(columns[::-1])
            boundary[1:] = False
            for c in columns:
                cs = c[perm]
                boundary[1:] |= cs[1:] != cs[:-1]
            break
    del same
    starts = np.flatnonzero(boundary)
    gid = np.cumsum(boundary, dtype=np.int64)
    gid -= 1
    first = np.minimum.reduceat(perm, starts)
    order = np.argsort(first, kind="stable")
    new_id = np.empty_like(order)
    new_id[order] = np.arange(order.shape[0], dtype=order.dtype)
    inverse = np.empty(k, dtype=np.int64)
    inverse[perm] = new_id[gid]
    unique = P[first[order]]
    return unique, inverse


@compiled
def _weld_table(key, c0, c1, c2, table, shift, inverse, first):
    """:func:`weld_exact` by open addressing: rows in order, each looked up by
    its hash's top bits (``table`` of size ``2**(64 - shift)``, -1 = empty,
    holds the row that opened a slot) and compared exactly on the bit-pattern columns ``c0``,
    ``c1`` and ``c2`` (empty when two columns identify a row); a new row gets
    the next id, so ids follow first appearance.  Returns the number of rows kept."""
    mask = table.shape[0] - 1
    three = c2.shape[0] > 0
    n = 0
    for r in range(key.shape[0]):
        h = int(key[r] >> np.uint64(shift)) & mask
        while True:
            s = table[h]
            if s < 0:
                table[h] = r
                inverse[r] = n
                first[n] = r
                n += 1
                break
            if c0[s] == c0[r] and c1[s] == c1[r] and (not three or c2[s] == c2[r]):
                inverse[r] = inverse[s]
                break
            h = (h + 1) & mask
    return n


def fan_triangulate(counts: np.ndarray, flat: np.ndarray) -> tuple[np.ndarray, int]:
    """Triangulate polygons as fans around their first corner.

    Polygon ``(a, b, c, d, ...)`` becomes ``(a, b, c), (a, c, d), ...``.
    Polygons with fewer than three corners are dropped.

    Parameters
    ----------
    counts : numpy.ndarray, (p,) int
        Corner count of each polygon.
    flat : numpy.ndarray, (sum(counts),) or (sum(counts), d)
        Per-corner values (vertex indices, or several index columns).

    Returns
    -------
    triangles : numpy.ndarray, (t, 3) or (t, 3, d)
    n_dropped : int
        Number of polygons with fewer than three corners.
    """
    counts = np.asarray(counts, dtype=np.int64)
    flat = np.asarray(flat)
    if counts.size and (counts == 3).all():
        return flat.reshape((-1, 3) + flat.shape[1:]), 0
    starts = np.zeros(counts.shape[0], dtype=np.int64)
    if counts.size > 1:
        np.cumsum(counts[:-1], out=starts[1:])
    ntri = np.maximum(counts - 2, 0)
    dropped = int(np.count_nonzero(counts < 3))
    total = int(ntri.sum())
    if total == 0:
        return flat[:0].reshape((0, 3) + flat.shape[1:]), dropped
    poly = np.repeat(np.arange(counts.shape[0]), ntri)
    first_tri = np.zeros(counts.shape[0], dtype=np.int64)
    if counts.size > 1:
        np.cumsum(ntri[:-1], out=first_tri[1:])
    j = np.arange(total, dtype=np.int64) - first_tri[poly] + 1
    base = starts[poly]
    corners = np.stack([base, base + j, base + j + 1], axis=1)
    return flat[corners], dropped


_SPACE_BYTES = np.zeros(256, dtype=bool)
_SPACE_BYTES[[9, 10, 11, 12, 13, 28, 29, 30, 31, 32]] = True


def tokens_per_line(block: str, n_lines: int) -> np.ndarray | None:
    """Count whitespace-separated tokens on each line of ``"\\n".join(lines)``.

    Returns None when the counts would not agree with :meth:`str.split`
    (non-ASCII whitespace); callers then take their line-by-line path.

    Returns
    -------
    numpy.ndarray, (n_lines,) int64 or None
    """
    raw = np.frombuffer(block.encode("utf-8", "surrogatepass"), dtype=np.uint8)
    if raw.size == 0:
        return np.zeros(n_lines, dtype=np.int64)
    if (raw >= 0x80).any() and any(ch.isspace() for ch in set(block) if ord(ch) >= 0x80):
        return None
    space = _SPACE_BYTES[raw]
    start = ~space
    start[1:] &= space[:-1]
    token_starts = np.flatnonzero(start)
    newlines = np.flatnonzero(raw == 10)
    if newlines.shape[0] + 1 != n_lines:
        return None
    before = np.empty(n_lines + 1, dtype=np.int64)
    before[0] = 0
    before[1:-1] = np.searchsorted(token_starts, newlines)
    before[-1] = token_starts.shape[0]
    return np.diff(before)


def token_table(lines: list[str]):
    """Split lines into tokens at once.

    Returns
    -------
    counts : numpy.ndarray, (len(lines),) int64
        Tokens on each line.
    values : numpy.ndarray or None
        All tokens as float64, or None when some token is not a number.
    tokens : list of str
        All tokens, line after line.
    """
    block = "\n".join(lines)
    tokens = block.split()
    counts = tokens_per_line(block, len(lines))
    if counts is not None and int(counts.sum()) != len(tokens):
        counts = None
    if counts is None:
        counts = np.fromiter((len(line.split()) for line in lines), dtype=np.int64,
                             count=len(lines))
    try:
        values = np.array(tokens, dtype=np.float64)
    except ValueError:
        values = None
    return counts, values, tokens


def line_starts(counts: np.ndarray) -> np.ndarray:
    """Index of each line's first token in the flat token list."""
    starts = np.zeros(counts.shape[0], dtype=np.int64)
    if counts.shape[0] > 1:
        np.cumsum(counts[:-1], out=starts[1:])
    return starts


class gc_paused:
    """Context manager pausing the cyclic garbage collector.

    Parsing text allocates millions of short-lived lists; the collector
    would scan them over and over for nothing (it doubles parse times).
    """

    def __enter__(self):
        import gc
        self._was_enabled = gc.isenabled()
        gc.disable()
        return self

    def __exit__(self, *exc):
        import gc
        if self._was_enabled:
            gc.enable()
        return False


def triangulate_polygons(counts: np.ndarray, flat: np.ndarray,
                         V: np.ndarray) -> tuple[np.ndarray, int]:
    """Split polygons into triangles without overlaps, also for concave outlines.

    Triangles pass through.  Other polygons go to
    :func:`geotex.mesh.polygons.polygon_triangle_corners`: quads are split
    along the diagonal that keeps both halves facing the polygon's normal
    (the shorter one when both do), larger polygons are ear-clipped in their
    best-fit plane, and a polygon the triangulator rejects is fanned around
    its first corner.  When some vertex index is out of range (the mesh
    constructor reports it afterwards) polygons are fanned.

    Parameters
    ----------
    counts : numpy.ndarray, (p,) int
        Corner count of each polygon.
    flat : numpy.ndarray, (sum(counts),) or (sum(counts), d) int64
        Per-corner indices; the vertex index is ``flat`` or ``flat[:, 0]``.
    V : numpy.ndarray, (n, 3) float64
        Vertex positions.

    Returns
    -------
    triangles : numpy.ndarray, (t, 3) or (t, 3, d) int64
    n_dropped : int
        Polygons with fewer than three corners (skipped).
    """
    counts = np.asarray(counts, dtype=np.int64)
    if counts.size and (counts == 3).all():
        return fan_triangulate(counts, flat)
    vertex = flat if flat.ndim == 1 else flat[:, 0]
    if vertex.size == 0 or vertex.min() < 0 or vertex.max() >= V.shape[0]:
        return fan_triangulate(counts, flat)

    corners, dropped = polygon_triangle_corners(counts, V[vertex])
    return flat[corners], dropped


def check_finite(path, V: np.ndarray, *, what: str = "vertex") -> None:
    """Raise :class:`MeshFileError` naming the first vertex with NaN or inf."""
    ok = np.isfinite(V)
    if ok.all():
        return
    bad = int(np.flatnonzero(~ok.all(axis=1))[0])
    raise MeshFileError(
        path, f"non-finite coordinates at {what} {bad}: {V[bad].tolist()} "
              "(NaN or infinity; the file is corrupt)")


def build_mesh(path, V, F, *, fmt: str, uv=None, uv_faces=None, texture=None,
               name: str | None = None, metadata: dict | None = None) -> Mesh:
    """Validate parsed arrays and wrap them in a :class:`Mesh`.

    Non-finite coordinates and out-of-range indices become
    :class:`MeshFileError` with the file path.
    """
    V = np.asarray(V, dtype=np.float64).reshape(-1, 3)
    check_finite(path, V)
    meta = {"format": fmt, "source": str(path)}
    if metadata:
        meta.update(metadata)
    try:
        return Mesh(V, np.asarray(F).reshape(-1, 3), uv=uv, uv_faces=uv_faces,
                    texture=texture, name=name if name is not None else _stem(path),
                    metadata=meta)
    except MeshFileError:
        raise
    except InputError as exc:
        raise MeshFileError(path, str(exc)) from None


def _stem(path) -> str:
    return Path(str(path)).stem


def decode_text(path, data: bytes, what: str) -> str:
    """Decode a text mesh file (UTF-8, else Latin-1; a leading BOM is dropped).

    NUL bytes mean binary content: :class:`MeshFileError`.
    """
    if b"\x00" in data:
        raise MeshFileError(path, f"binary content, not a text {what} file")
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def first_bad_number(tokens, convert=float) -> str:
    """Return the first token ``convert`` rejects, for error messages ("?" if none)."""
    for token in tokens:
        try:
            convert(token)
        except (TypeError, ValueError, OverflowError):
            if isinstance(token, bytes):
                token = token.decode("latin-1")
            return str(token)[:40]
    return "?"


def format_rows(fmt_row: str, values: np.ndarray) -> str:
    """Format every row of ``values`` with the %-template ``fmt_row``.

    ``values`` is converted to Python scalars first, so ``%r`` gives the
    shortest text that reads back to exactly the same float64.
    """
    values = np.asarray(values)
    n = values.shape[0]
    if n == 0:
        return ""
    flat = values.reshape(n, -1).ravel().tolist()
    return (fmt_row * n) % tuple(flat)


def per_vertex_uv(mesh: Mesh) -> np.ndarray | None:
    """Return ``(n, 2)`` uv when every vertex has a single uv value, else None.

    Unreferenced vertices get ``(0, 0)``.
    """
    if mesh.uv is None:
        return None
    corner_uv = mesh.uv[mesh.uv_faces].reshape(-1, 2)
    corner_v = mesh.faces.ravel()
    out = np.zeros((mesh.n_vertices, 2))
    out[corner_v] = corner_uv
    if not np.array_equal(out[corner_v], corner_uv):
        return None
    return out
