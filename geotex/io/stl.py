"""STL reading (ASCII and binary) and writing.

Reading
    A file is binary when its size is exactly ``84 + 50 * count`` with
    ``count`` the little-endian triangle count at byte 80.  This size rule is
    applied first, because binary files whose 80-byte header starts with
    ``solid`` exist.  Otherwise a file starting with ``solid`` is ASCII; it may
    hold several ``solid ... endsolid`` blocks (all are merged), any
    whitespace, upper or lower case keywords and numbers in any notation.
    STL stores every triangle with its own three corners: corners with
    exactly equal coordinates are welded into one vertex (``-0.0`` equals
    ``0.0``), vertices are numbered in order of first appearance.  Stored
    normals and the binary attribute bytes are ignored.

Writing
    Binary (default): float32 little endian, unit normals computed from the
    geometry (zero for degenerate triangles), an 80-byte header that does not
    start with ``solid``.  Large meshes are written by a compiled loop in
    chunks of ``WRITE_CHUNK`` facets (the same bytes as the numpy path: the
    same float64 cross products and norms, no ``(m, 3, 3)`` temporaries).  ASCII (``binary=False``): coordinates written with
    ``repr`` (the shortest text that reads back to the same float64), so an
    ASCII round trip is exact.
"""

from __future__ import annotations

import re
import struct

import numpy as np

from geotex.errors import MeshFileError
from geotex.io._common import build_mesh, first_bad_number, format_rows, weld_exact
from geotex.jit import JIT_MIN_SIZE, compiled
from geotex.mesh.geometry import face_normals

__all__ = ["read_stl", "write_stl", "STL_DTYPE"]

STL_DTYPE = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)),
                      ("attribute", "<u2")])

#: Facets per chunk of the compiled binary writer.
WRITE_CHUNK = 1 << 16

_HEADER = b"geotex binary STL (float32, little endian)".ljust(80, b" ")

_FACET = re.compile(
    rb"\bfacet\s+normal\s+\S+\s+\S+\s+\S+\s+outer\s+loop\s+"
    rb"vertex\s+(\S+)\s+(\S+)\s+(\S+)\s+"
    rb"vertex\s+(\S+)\s+(\S+)\s+(\S+)\s+"
    rb"vertex\s+(\S+)\s+(\S+)\s+(\S+)\s+"
    rb"endloop\s+endfacet(?=\s|\Z)", re.IGNORECASE)
_LINE = re.compile(rb"\S[^\n\r]*")
_SOLID_START = re.compile(rb"\s*solid(?:\s|\Z)", re.IGNORECASE)


def read_stl(path, data: bytes):
    """Parse STL bytes into a :class:`~geotex.mesh.Mesh` (see module notes).

    Raises
    ------
    MeshFileError
        On a truncated binary file (the message gives the expected size), a
        malformed ASCII facet, or non-finite coordinates.
    """
    size = len(data)
    count = struct.unpack_from("<I", data, 80)[0] if size >= 84 else None
    if count is not None and 84 + 50 * count == size:
        return _read_binary(path, data, count)
    text = data[3:] if data.startswith(b"\xef\xbb\xbf") else data      # UTF-8 BOM
    if _SOLID_START.match(text[:4096]):
        try:
            return _read_ascii(path, text)
        except MeshFileError as exc:
            if count is None:
                raise
            expected = 84 + 50 * count
            raise MeshFileError(
                path, f"{exc.reason}; it is not a binary STL either (the header "
                      f"announces {count} triangles, which needs {expected} bytes, "
                      f"but the file has {size} bytes)") from None
    if count is None:
        raise MeshFileError(
            path, f"not an STL file: {size} bytes is too short for a binary STL "
                  "(at least 84 bytes) and an ASCII STL starts with 'solid'")
    expected = 84 + 50 * count
    if size < expected <= 2 * size:
        raise MeshFileError(
            path, f"binary STL is truncated: the header announces {count} triangles, "
                  f"which needs {expected} bytes, but the file has {size} bytes")
    if size < expected:
        raise MeshFileError(
            path, f"not an STL file: read as a binary STL its header announces {count} "
                  f"triangles, which needs {expected} bytes, but the file has {size} bytes, "
                  "and it does not start with 'solid' as an ASCII STL must")
    raise MeshFileError(
        path, f"not a valid binary STL: the header announces {count} triangles, "
              f"which needs {expected} bytes, but the file has {size} bytes "
              f"({size - expected} extra)")


def _weld_corners(path, P: np.ndarray, fmt_meta: dict):
    """Check corner coordinates, weld them, and build the mesh."""
    finite = np.isfinite(P)
    if not finite.all():        # (a reduction along rows of 3 costs 20x the flat one)
        bad = int(np.flatnonzero(~finite.all(axis=1))[0])
        raise MeshFileError(
            path, f"non-finite coordinates at vertex {bad} (facet {bad // 3}, corner "
                  f"{bad % 3}): {P[bad].tolist()} (NaN or infinity; the file is corrupt)")
    del finite
    unique, inverse = weld_exact(P)
    V = unique.astype(np.float64)
    F = inverse.reshape(-1, 3)
    return build_mesh(path, V, F, fmt="stl", metadata=fmt_meta)


def _read_binary(path, data: bytes, count: int):
    rec = np.frombuffer(data, dtype=STL_DTYPE, count=count, offset=84)
    P = rec["vertices"].reshape(-1, 3)
    return _weld_corners(path, P, {"stl_encoding": "binary"})


def _line_number(data: bytes, pos: int) -> int:
    return data.count(b"\n", 0, pos) + 1


def _piece_offset(data: bytes, piece: int) -> int:
    """Byte offset of the text between facet ``piece - 1`` and facet ``piece``."""
    if piece == 0:
        return 0
    for i, match in enumerate(_FACET.finditer(data)):
        if i == piece - 1:
            return match.end()
    return len(data)


def _read_ascii(path, data: bytes):
    if b"\x00" in data:
        raise MeshFileError(path, "not an ASCII STL: it starts with 'solid' but has "
                                  "binary content")
    parts = _FACET.split(data)
    between = parts[0::10]
    n_facets = len(between) - 1

    def fail(piece: int, local: int, message: str):
        line = _line_number(data, _piece_offset(data, piece) + local)
        raise MeshFileError(path, f"ASCII STL line {line}: {message}")

    inside = False
    last = 0
    nonblank = [i for i, piece in enumerate(between) if piece and not piece.isspace()]
    for p in nonblank:
        if p > last and not inside:
            fail(last, len(between[last]), "facet outside a 'solid ... endsolid' block")
        for match in _LINE.finditer(between[p]):
            tokens = match.group().split()
            keyword = tokens[0].lower()
            if keyword == b"solid":
                if inside:
                    fail(p, match.start(), "'solid' inside another solid "
                                           "(missing 'endsolid')")
                inside = not any(t.lower() == b"endsolid" for t in tokens[1:])
            elif keyword == b"endsolid":
                if not inside:
                    fail(p, match.start(), "'endsolid' without a matching 'solid'")
                inside = False
            else:
                word = tokens[0].decode("latin-1")[:40]
                fail(p, match.start(),
                     f"malformed facet near {word!r} (expected 'facet normal nx ny nz', "
                     "'outer loop', three 'vertex x y z', 'endloop', 'endfacet')")
        last = p
    if last < n_facets and not inside:
        fail(last, len(between[last]), "facet outside a 'solid ... endsolid' block")
    if inside:
        raise MeshFileError(path, "ASCII STL ends without 'endsolid' (truncated file?)")
    if n_facets == 0:
        P = np.zeros((0, 3))
    else:
        del parts[0::10]                 # keep the nine coordinates of each facet
        try:
            P = np.array(parts, dtype=np.float64).reshape(-1, 3)
        except ValueError:
            raise MeshFileError(path, f"ASCII STL has a malformed vertex coordinate "
                                      f"{first_bad_number(parts)!r}") from None
    return _weld_corners(path, P, {"stl_encoding": "ascii"})


def write_stl(fh, mesh, *, path, binary: bool = True) -> None:
    """Write ``mesh`` as STL to the open binary file ``fh`` (see module notes).

    Raises
    ------
    MeshFileError
        For a binary file, if a coordinate exceeds the float32 range.
    """
    V, F = mesh.vertices, mesh.faces
    if binary:
        if V.size and np.abs(V).max() > np.finfo(np.float32).max:
            raise MeshFileError(path, "coordinates exceed the float32 range of binary "
                                      "STL; write an ASCII STL instead")
        if F.size >= JIT_MIN_SIZE:
            _write_binary_chunks(fh, V, F)
            return
        rec = np.zeros(F.shape[0], dtype=STL_DTYPE)
        V32 = V.astype(np.float32)
        # normals of the facets as stored (float32 corners), so a reader that
        # recomputes them (admesh) finds nothing to fix
        rec["normal"] = face_normals(V32.astype(np.float64), F)
        rec["vertices"] = V32[F]            # float32 corners: half the memory of float64 ones
        fh.write(_HEADER)
        fh.write(struct.pack("<I", F.shape[0]))
        fh.write(rec.tobytes())
        return
    name = " ".join((mesh.name or "geotex").split()) or "geotex"
    # Format each vertex and normal once, then assemble the facets from strings.
    vertex_text = np.array(format_rows("%r %r %r\n", V).split("\n")[:-1], dtype=object)
    cells = np.empty((F.shape[0], 4), dtype=object)
    cells[:, 0] = format_rows("%r %r %r\n", face_normals(V, F)).split("\n")[:-1]
    cells[:, 1:] = vertex_text[F] if F.shape[0] else cells[:, 1:]
    row = ("facet normal %s\n outer loop\n  vertex %s\n  vertex %s\n  vertex %s\n"
           " endloop\nendfacet\n")
    body = (row * F.shape[0]) % tuple(cells.ravel().tolist()) if F.shape[0] else ""
    fh.write(f"solid {name}\n{body}endsolid {name}\n".encode("utf-8"))


def _write_binary_chunks(fh, V, F) -> None:
    """The binary body of :func:`write_stl` by :func:`_facet_rows`, chunk by chunk."""
    m = F.shape[0]
    V32 = V.astype(np.float32).astype(np.float64)
    F = np.ascontiguousarray(F, dtype=np.int64)
    fh.write(_HEADER)
    fh.write(struct.pack("<I", m))
    rows = np.empty((min(m, WRITE_CHUNK), 12), dtype="<f4")
    buf = np.zeros((rows.shape[0], STL_DTYPE.itemsize), dtype=np.uint8)   # attribute bytes 0
    for s in range(0, m, WRITE_CHUNK):
        k = min(WRITE_CHUNK, m - s)
        _facet_rows(V32, F[s:s + k], rows)
        buf[:k, :48] = rows[:k].view(np.uint8)
        fh.write(buf[:k].data)


@compiled
def _facet_rows(V, F, rows):
    """Normal and corners of each facet as float32 rows: the normal is
    :func:`geotex.mesh.geometry.face_normals`' (float64 cross product of the
    corners as given, divided by its norm ``sqrt((x² + y²) + z²)``, zero when
    degenerate), then rounded."""
    for f in range(F.shape[0]):
        i, j, k = F[f, 0], F[f, 1], F[f, 2]
        a0 = V[j, 0] - V[i, 0]
        a1 = V[j, 1] - V[i, 1]
        a2 = V[j, 2] - V[i, 2]
        b0 = V[k, 0] - V[i, 0]
        b1 = V[k, 1] - V[i, 1]
        b2 = V[k, 2] - V[i, 2]
        c0 = a1 * b2 - a2 * b1
        c1 = a2 * b0 - a0 * b2
        c2 = a0 * b1 - a1 * b0
        n = np.sqrt((c0 * c0 + c1 * c1) + c2 * c2)
        if n > 0:
            rows[f, 0] = c0 / n
            rows[f, 1] = c1 / n
            rows[f, 2] = c2 / n
        else:
            rows[f, 0] = 0.0
            rows[f, 1] = 0.0
            rows[f, 2] = 0.0
        for c in range(3):
            v = F[f, c]
            for x in range(3):
                rows[f, 3 + 3 * c + x] = V[v, x]
