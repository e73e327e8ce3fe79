"""PLY reading (ASCII, binary little and big endian) and writing.

Reading
    The ``vertex`` element must have ``x``, ``y`` and ``z`` properties of any
    PLY scalar type (``char uchar short ushort int uint float double`` or the
    ``int8 ... float64`` names); its other properties, lists included, are
    skipped.  Per-vertex texture coordinates (``s t``, ``u v``,
    ``texture_u texture_v`` or ``texture_s texture_t``) become ``uv`` with
    ``uv_faces == faces``.  Colours (``red green blue`` and the like, on the
    vertex and face elements) are read by :func:`read_ply_colors` only.  The
    ``face`` element's list property ``vertex_indices`` (or ``vertex_index``)
    may use any count and index types; polygons are triangulated without overlaps, concave ones included
    (see :func:`geotex.io._common.triangulate_polygons`), and faces with
    fewer than three corners are skipped (counted in
    ``metadata["skipped_faces"]``).  Any other element (edges, materials,
    ...) is skipped, in binary files too.  A file without a face element is a
    point cloud: a mesh with no faces.

    Speed: an element whose list properties have the same length in every
    record (all triangles, the usual case) is parsed with one structured
    numpy dtype; otherwise records are located with a loop over the records
    (binary) or tokens (ASCII) and the values gathered with numpy.

Writing
    Binary little endian (default) with ``double`` x, y, z, so a round trip is
    exact, and ``uchar`` + ``int`` face lists.  ``binary=False`` writes ASCII
    with ``repr`` coordinates (also exact).  Per-vertex ``s``, ``t`` are
    written when the mesh has uv and every vertex has a single uv value;
    otherwise uv is not written.
"""

from __future__ import annotations

import re
import struct

import numpy as np

from geotex.errors import MeshFileError
from geotex.io._common import (build_mesh, first_bad_number, format_rows, per_vertex_uv,
                               triangulate_polygons)

__all__ = ["read_ply", "read_ply_colors", "write_ply", "PLY_TYPES"]

PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
_FORMATS = {"ascii": None, "binary_little_endian": "<", "binary_big_endian": ">"}
_END_HEADER = re.compile(rb"(?:\r?\n)end_header[ \t]*(?:\r?\n|\Z)")
_UV_NAMES = (("s", "t"), ("u", "v"), ("texture_u", "texture_v"), ("texture_s", "texture_t"))
_FACE_LISTS = ("vertex_indices", "vertex_index")
_COLOR_NAMES = (("red", "green", "blue"), ("r", "g", "b"),
                ("diffuse_red", "diffuse_green", "diffuse_blue"))


class _Property:
    __slots__ = ("name", "dtype", "count_dtype")

    def __init__(self, name, dtype, count_dtype=None):
        self.name = name
        self.dtype = dtype              # value type (items for a list)
        self.count_dtype = count_dtype  # None for a scalar property

    @property
    def is_list(self) -> bool:
        return self.count_dtype is not None


class _Element:
    __slots__ = ("name", "count", "props", "line")

    def __init__(self, name, count, line):
        self.name = name
        self.count = count
        self.props: list[_Property] = []
        self.line = line

    def prop(self, name):
        return next((p for p in self.props if p.name == name), None)


def _parse_header(path, data: bytes):
    if not re.match(rb"ply[ \t]*\r?\n", data):
        raise MeshFileError(path, "not a PLY file: the first line must be 'ply'")
    match = _END_HEADER.search(data)
    if match is None:
        raise MeshFileError(path, "PLY header has no 'end_header' line (truncated or "
                                  "not a PLY file)")
    header = data[:match.start()].decode("latin-1")
    lines = header.splitlines()
    fmt = None
    elements: list[_Element] = []
    for lineno, line in enumerate(lines[1:], 2):
        tokens = line.split()
        if not tokens or tokens[0] in ("comment", "obj_info"):
            continue

        def bad(msg, lineno=lineno):
            raise MeshFileError(path, f"bad PLY header line {lineno}: {msg}")

        key = tokens[0]
        if key == "format":
            if len(tokens) < 2 or tokens[1] not in _FORMATS:
                bad(f"unknown format {' '.join(tokens[1:2])!r} (expected ascii, "
                    "binary_little_endian or binary_big_endian)")
            fmt = tokens[1]
        elif key == "element":
            if len(tokens) != 3 or not (tokens[2].isascii() and tokens[2].isdigit()) \
                    or len(tokens[2]) > 19:
                bad("expected 'element NAME COUNT' with a non-negative integer count")
            elements.append(_Element(tokens[1], int(tokens[2]), lineno))
        elif key == "property":
            if not elements:
                bad("property before any element")
            if len(tokens) >= 2 and tokens[1] == "list":
                if len(tokens) != 5:
                    bad("expected 'property list COUNT_TYPE ITEM_TYPE NAME'")
                for t in tokens[2:4]:
                    if t not in PLY_TYPES:
                        bad(f"unknown type {t!r}")
                if PLY_TYPES[tokens[2]][0] == "f":
                    bad(f"list count type must be an integer type, got {tokens[2]!r}")
                elements[-1].props.append(
                    _Property(tokens[4], PLY_TYPES[tokens[3]], PLY_TYPES[tokens[2]]))
            else:
                if len(tokens) != 3:
                    bad("expected 'property TYPE NAME'")
                if tokens[1] not in PLY_TYPES:
                    bad(f"unknown type {tokens[1]!r}")
                elements[-1].props.append(_Property(tokens[2], PLY_TYPES[tokens[1]]))
        else:
            bad(f"unknown keyword {key[:40]!r}")
    if fmt is None:
        raise MeshFileError(path, "bad PLY header: no 'format' line")
    return fmt, elements, match.end()


def read_ply(path, data: bytes):
    """Parse PLY bytes into a :class:`~geotex.mesh.Mesh` (see module notes).

    Raises
    ------
    MeshFileError
        On a bad header, missing ``x y z``, truncated data (the message gives
        the number of bytes or values expected), or non-finite coordinates.
    """
    return _read_ply(path, data, colors=False)[0]


def read_ply_colors(path, data: bytes):
    """Parse PLY bytes into a mesh and its per-face and per-vertex colours.

    Colours are the ``red green blue`` properties (also ``r g b`` or
    ``diffuse_red diffuse_green diffuse_blue``; alpha is ignored) of the
    ``face`` and ``vertex`` elements, of any scalar type.  Integer types are
    read as 0..255; float types as 0..1 when no value exceeds 1, else as
    0..255.  A polygon's colour goes to every triangle it is split into.

    Returns
    -------
    mesh : geotex.mesh.Mesh
    face_colors : numpy.ndarray, (m, 3) float64 or None
        Per triangle, 0..255.
    vertex_colors : numpy.ndarray, (n, 3) float64 or None
        0..255.

    Raises
    ------
    MeshFileError
        As :func:`read_ply`, and for non-finite or negative colours.
    """
    return _read_ply(path, data, colors=True)


def _color_names(element):
    """The names of the scalar colour properties of ``element``, or None."""
    if element is None:
        return None
    return next((names for names in _COLOR_NAMES
                 if all(element.prop(n) is not None and not element.prop(n).is_list
                        for n in names)), None)


def _colors(path, vals, names, element, what):
    """(k, 3) float64 colours in 0..255 from the parsed property columns."""
    C = np.stack([np.asarray(vals[n], dtype=np.float64) for n in names], axis=1)
    if not np.isfinite(C).all() or (C < 0).any():
        bad = int(np.flatnonzero(~(np.isfinite(C) & (C >= 0)).all(axis=1))[0])
        raise MeshFileError(path, f"PLY {what} {bad} has the colour {C[bad].tolist()} "
                                  "(colours must be finite and non-negative)")
    if all(element.prop(n).dtype[0] == "f" for n in names) and (C.size == 0 or C.max() <= 1.0):
        C = C * 255.0
    return C


def _read_ply(path, data: bytes, *, colors: bool):
    fmt, elements, body_start = _parse_header(path, data)
    vertex = next((e for e in elements if e.name == "vertex"), None)
    if vertex is None:
        raise MeshFileError(path, "PLY file has no 'vertex' element")
    missing = [c for c in "xyz" if vertex.prop(c) is None or vertex.prop(c).is_list]
    if missing:
        raise MeshFileError(path, "PLY vertex element lacks the scalar properties "
                                  f"{', '.join(missing)} (x, y, z are required)")
    face = next((e for e in elements if e.name == "face"), None)
    face_list = None
    if face is not None:
        face_list = next((face.prop(n) for n in _FACE_LISTS
                          if face.prop(n) is not None and face.prop(n).is_list), None)
        if face_list is None and face.count:
            raise MeshFileError(path, "PLY face element has no 'vertex_indices' list "
                                      "property")
    uv_names = next((pair for pair in _UV_NAMES
                     if all(vertex.prop(n) is not None and not vertex.prop(n).is_list
                            for n in pair)), None)
    v_colors = _color_names(vertex) if colors else None
    f_colors = _color_names(face) if colors and face_list is not None else None
    wanted = {"vertex": ["x", "y", "z"] + list(uv_names or ()) + list(v_colors or ())}
    if face_list is not None:
        wanted["face"] = [face_list.name] + list(f_colors or ())
    if _FORMATS[fmt] is None:
        values = _read_ascii_body(path, data[body_start:], elements, wanted)
    else:
        values = _read_binary_body(path, data, body_start, _FORMATS[fmt], elements, wanted)
    vals = values["vertex"]
    V = np.stack([vals["x"], vals["y"], vals["z"]], axis=1).astype(np.float64)
    uv = None
    if uv_names is not None:
        uv = np.stack([vals[uv_names[0]], vals[uv_names[1]]], axis=1).astype(np.float64)
    vertex_rgb = None if v_colors is None else _colors(path, vals, v_colors, vertex, "vertex")
    face_rgb = None
    F = np.zeros((0, 3), dtype=np.int64)
    skipped = 0
    if "face" in values:
        counts, flat = values["face"][face_list.name]
        flat = flat.astype(np.int64)
        if f_colors is None:
            F, skipped = triangulate_polygons(counts, flat, V)
        else:
            # the polygon of every corner rides along, so each triangle knows its polygon
            poly = np.repeat(np.arange(counts.shape[0], dtype=np.int64), counts)
            T, skipped = triangulate_polygons(counts, np.stack([flat, poly], axis=1), V)
            F = T[:, :, 0]
            rgb = _colors(path, values["face"], f_colors, face, "face")
            face_rgb = rgb[T[:, 0, 1]]
    meta = {"ply_format": fmt}
    if skipped:
        meta["skipped_faces"] = skipped
    mesh = build_mesh(path, V, F, fmt="ply", uv=uv, uv_faces=F if uv is not None else None,
                      metadata=meta)
    return mesh, face_rgb, vertex_rgb


# --------------------------------------------------------------------------- binary


def _truncated(path, element, need, have, offset, total):
    raise MeshFileError(
        path, f"binary PLY is truncated: element {element.name!r} needs {need} bytes at "
              f"byte {offset} but only {have} remain (the file has {total} bytes, at "
              f"least {offset + need} expected)")


def _scalar_dtype(element, endian):
    return np.dtype([(f"p{i}", endian + p.dtype) for i, p in enumerate(element.props)])


def _read_binary_body(path, data, offset, endian, elements, wanted):
    total = len(data)
    out = {}
    for el in elements:
        names = wanted.get(el.name)
        if not any(p.is_list for p in el.props):
            dt = _scalar_dtype(el, endian)
            need = el.count * dt.itemsize
            if offset + need > total:
                _truncated(path, el, need, total - offset, offset, total)
            if names:
                rec = np.frombuffer(data, dtype=dt, count=el.count, offset=offset)
                out[el.name] = {p.name: rec[f"p{i}"] for i, p in enumerate(el.props)
                                if p.name in names}
            offset += need
            continue
        result, offset = _binary_list_element(path, data, offset, endian, el, names)
        if names:
            out[el.name] = result
    return out


def _first_record_counts(data, offset, endian, el):
    """List lengths in the first record of ``el`` (None if it runs past the end)."""
    counts = []
    pos = offset
    for p in el.props:
        if p.is_list:
            size = np.dtype(p.count_dtype).itemsize
            if pos + size > len(data):
                return None
            c = int(np.frombuffer(data, endian + p.count_dtype, 1, pos)[0])
            if c < 0:
                return None
            counts.append(c)
            pos += size + c * np.dtype(p.dtype).itemsize
        else:
            pos += np.dtype(p.dtype).itemsize
    return counts


def _binary_list_element(path, data, offset, endian, el, names):
    """Parse an element with list properties; return (values, new offset)."""
    total = len(data)
    if el.count == 0:
        return _empty_values(el, names), offset
    counts = _first_record_counts(data, offset, endian, el)
    if counts is not None:
        fields = []
        k = iter(counts)
        for i, p in enumerate(el.props):
            if p.is_list:
                fields.append((f"c{i}", endian + p.count_dtype))
                fields.append((f"p{i}", endian + p.dtype, (next(k),)))
            else:
                fields.append((f"p{i}", endian + p.dtype))
        dt = np.dtype(fields)
        need = el.count * dt.itemsize
        if offset + need <= total:
            rec = np.frombuffer(data, dtype=dt, count=el.count, offset=offset)
            k = iter(counts)
            uniform = all((rec[f"c{i}"] == next(k)).all()
                          for i, p in enumerate(el.props) if p.is_list)
            if uniform:
                values = {}
                k = iter(counts)
                for i, p in enumerate(el.props):
                    c = next(k) if p.is_list else None
                    if not names or p.name not in names:
                        continue
                    if p.is_list:
                        values[p.name] = (np.full(el.count, c, dtype=np.int64),
                                          rec[f"p{i}"].reshape(-1))
                    else:
                        values[p.name] = rec[f"p{i}"]
                return values, offset + need
    return _binary_list_walk(path, data, offset, endian, el, names)


def _empty_values(el, names):
    values = {}
    for p in el.props:
        if names and p.name in names:
            values[p.name] = ((np.zeros(0, np.int64), np.zeros(0, p.dtype)) if p.is_list
                              else np.zeros(0, p.dtype))
    return values


def _binary_list_walk(path, data, offset, endian, el, names):
    """Locate every record with a loop, then gather the wanted values with numpy."""
    total = len(data)
    plan = []
    for p in el.props:
        size = np.dtype(p.dtype).itemsize
        if p.is_list:
            cdt = np.dtype(p.count_dtype)
            plan.append((struct.Struct(endian + cdt.char), cdt.itemsize, size))
        else:
            plan.append((None, size, 0))
    min_size = sum(step for _, step, _ in plan)
    if offset + el.count * min_size > total:
        _truncated(path, el, el.count * min_size, total - offset, offset, total)
    keep = [i for i, p in enumerate(el.props) if names and p.name in names]
    positions = {i: [] for i in keep}
    lengths = {i: [] for i in keep if el.props[i].is_list}
    pos = offset
    start = offset
    for _ in range(el.count):
        for i, (fmt, step, item) in enumerate(plan):
            if i in positions:
                positions[i].append(pos)
            if fmt is None:
                pos += step
            else:
                if pos + step > total:
                    _truncated(path, el, pos + step - start, total - start, start, total)
                c = fmt.unpack_from(data, pos)[0]
                if c < 0:
                    raise MeshFileError(path, f"binary PLY element {el.name!r} has a "
                                              f"negative list length {c}")
                if i in lengths:
                    lengths[i].append(c)
                pos += step + c * item
    if pos > total:
        _truncated(path, el, pos - start, total - start, start, total)
    buf = np.frombuffer(data, dtype=np.uint8)
    values = {}
    for i in keep:
        p = el.props[i]
        dt = np.dtype(endian + p.dtype)
        at = np.asarray(positions[i], dtype=np.int64)
        if p.is_list:
            c = np.asarray(lengths[i], dtype=np.int64)
            first = at + np.dtype(p.count_dtype).itemsize
            item_pos = _list_item_positions(first, c, dt.itemsize)
            values[p.name] = (c, _gather(buf, item_pos, dt))
        else:
            values[p.name] = _gather(buf, at, dt)
    return values, pos


def _list_item_positions(first: np.ndarray, counts: np.ndarray, itemsize: int) -> np.ndarray:
    """Byte offsets of every list item, given each list's first item offset."""
    total = int(counts.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    starts = np.zeros(counts.shape[0], dtype=np.int64)
    np.cumsum(counts[:-1], out=starts[1:])
    within = np.arange(total, dtype=np.int64) - np.repeat(starts, counts)
    return np.repeat(first, counts) + within * itemsize


def _gather(buf: np.ndarray, at: np.ndarray, dt: np.dtype) -> np.ndarray:
    """Read one value of type ``dt`` at each byte offset in ``at``."""
    idx = at[:, None] + np.arange(dt.itemsize, dtype=np.int64)
    return buf[idx].reshape(-1).view(dt)


# --------------------------------------------------------------------------- ASCII


def _read_ascii_body(path, body: bytes, elements, wanted):
    tokens = body.split()
    n_tokens = len(tokens)
    pos = 0
    out = {}

    def short(el, need):
        raise MeshFileError(
            path, f"ASCII PLY is truncated: element {el.name!r} needs at least {need} "
                  f"values but only {n_tokens - pos} remain")

    def numbers(chunk):
        try:
            return np.array(chunk, dtype=np.float64)
        except ValueError:
            raise MeshFileError(path, f"ASCII PLY has a bad number "
                                      f"{first_bad_number(chunk)!r}") from None

    for el in elements:
        names = wanted.get(el.name)
        nprops = len(el.props)
        if not any(p.is_list for p in el.props):
            need = el.count * nprops
            if pos + need > n_tokens:
                short(el, need)
            if names:
                table = numbers(tokens[pos:pos + need]).reshape(el.count, nprops)
                out[el.name] = {p.name: table[:, i] for i, p in enumerate(el.props)
                                if p.name in names}
            pos += need
            continue
        if pos + el.count * nprops > n_tokens:
            short(el, el.count * nprops)
        values, pos = _ascii_list_element(path, tokens, pos, el, names, numbers, short)
        if names:
            out[el.name] = values
    return out


def _ascii_list_element(path, tokens, pos, el, names, numbers, short):
    if el.count == 0:
        return _empty_values(el, names), pos
    n_tokens = len(tokens)
    # Fast path: the lists of the first record give a fixed record length.
    counts = []
    p_at = pos
    try:
        for p in el.props:
            if p.is_list:
                c = int(float(tokens[p_at]))
                counts.append(c)
                p_at += 1 + c
            else:
                p_at += 1
    except (IndexError, ValueError, OverflowError):     # the general path reports it
        counts = None
    if counts is not None and min(counts, default=0) >= 0:
        width = p_at - pos
        need = el.count * width
        if pos + need <= n_tokens:
            table = numbers(tokens[pos:pos + need]).reshape(el.count, width)
            col = 0
            uniform = True
            layout = []
            k = iter(counts)
            for p in el.props:
                if p.is_list:
                    c = next(k)
                    if not (table[:, col] == c).all():
                        uniform = False
                        break
                    layout.append((p, col + 1, c))
                    col += 1 + c
                else:
                    layout.append((p, col, None))
                    col += 1
            if uniform:
                values = {}
                for p, col, c in layout:
                    if names and p.name in names:
                        if c is None:
                            values[p.name] = table[:, col]
                        else:
                            values[p.name] = (np.full(el.count, c, dtype=np.int64),
                                              _as_index(path, table[:, col:col + c]))
                return values, pos + need
    # General path: walk the records token by token.
    keep = [i for i, p in enumerate(el.props) if names and p.name in names]
    positions = {i: [] for i in keep}
    lengths = {i: [] for i in keep if el.props[i].is_list}
    at = pos
    try:
        for _ in range(el.count):
            for i, p in enumerate(el.props):
                if i in positions:
                    positions[i].append(at)
                if p.is_list:
                    c = int(float(tokens[at]))
                    if c < 0:
                        raise MeshFileError(path, f"ASCII PLY element {el.name!r} has a "
                                                  f"negative list length {c}")
                    if i in lengths:
                        lengths[i].append(c)
                    at += 1 + c
                else:
                    at += 1
    except IndexError:
        short(el, at - pos + 1)
    except (ValueError, OverflowError):         # "nan", "inf", "x"
        raise MeshFileError(path, f"ASCII PLY element {el.name!r} has a bad list "
                                  f"length {tokens[at][:40]!r}") from None
    if at > n_tokens:
        short(el, at - pos)
    values = {}
    for i in keep:
        p = el.props[i]
        starts = np.asarray(positions[i], dtype=np.int64)
        if p.is_list:
            c = np.asarray(lengths[i], dtype=np.int64)
            idx = _list_item_positions(starts + 1, c, 1)
            chunk = [tokens[j] for j in idx.tolist()]
            values[p.name] = (c, _as_index(path, numbers(chunk)))
        else:
            values[p.name] = numbers([tokens[j] for j in starts.tolist()])
    return values, at


def _as_index(path, values: np.ndarray) -> np.ndarray:
    flat = values.reshape(-1)
    if flat.size and not (np.isfinite(flat).all() and (flat == np.round(flat)).all()):
        raise MeshFileError(path, "ASCII PLY face list holds a non-integer vertex index")
    if flat.size and np.abs(flat).max() >= 2.0 ** 62:
        raise MeshFileError(path, f"ASCII PLY face list holds the vertex index "
                                  f"{float(flat[np.abs(flat).argmax()]):g}, far out of range")
    return flat.astype(np.int64)


# --------------------------------------------------------------------------- writing


def write_ply(fh, mesh, *, path, binary: bool = True) -> None:
    """Write ``mesh`` as PLY to the open binary file ``fh`` (see module notes)."""
    V, F = mesh.vertices, mesh.faces
    uv = per_vertex_uv(mesh)
    fmt = "binary_little_endian" if binary else "ascii"
    props = ["property double x", "property double y", "property double z"]
    if uv is not None:
        props += ["property double s", "property double t"]
    header = "\n".join(
        ["ply", f"format {fmt} 1.0", "comment written by geotex",
         f"element vertex {V.shape[0]}", *props,
         f"element face {F.shape[0]}", "property list uchar int vertex_indices",
         "end_header"]) + "\n"
    fh.write(header.encode("ascii"))
    values = V if uv is None else np.concatenate([V, uv], axis=1)
    if binary:
        if V.shape[0] > np.iinfo(np.int32).max:
            raise MeshFileError(path, "too many vertices for 32-bit PLY face indices")
        fh.write(np.ascontiguousarray(values, dtype="<f8").tobytes())
        rec = np.empty(F.shape[0], dtype=[("n", "u1"), ("i", "<i4", (3,))])
        rec["n"] = 3
        rec["i"] = F
        fh.write(rec.tobytes())
        return
    row = " ".join(["%r"] * values.shape[1]) + "\n"
    fh.write(format_rows(row, values).encode("ascii"))
    fh.write(format_rows("3 %d %d %d\n", F).encode("ascii"))
