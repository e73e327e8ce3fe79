"""Wavefront OBJ reading and writing, with an MTL + PNG texture.

Reading
    ``v x y z [w | r g b ...]`` (only x, y, z are used; extra columns such as
    vertex colours, even ``nan`` ones, are ignored; :func:`read_obj_colors`
    reads ``r g b`` too), ``vt u [v [w]]``, and
    ``f`` corners written ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn``.  Indices
    start at 1; negative indices count back from the last vertex defined
    before the face.  Polygons with more than three corners are triangulated
    without overlaps, concave ones included: quads along the diagonal that
    keeps both halves facing the polygon's normal (the shorter one when both
    do; a square ``a b c d`` gives ``a b c``, ``a c d``), larger polygons by
    ear clipping in their best-fit plane (:mod:`geotex.mesh.polygons`), a
    polygon the triangulator rejects as a fan around its first corner.  Faces
    with fewer than three corners are skipped and counted in
    ``metadata["skipped_faces"]``.  A
    trailing backslash joins a line with the next; ``#`` starts a comment;
    ``vn``, ``vp``, ``o``, ``g``, ``s``, ``usemtl``, ``l``, ``p`` and
    free-form geometry statements are ignored.  Texture coordinates are kept
    (``uv``, ``uv_faces``) only when every face has them.  ``mtllib``: when
    the MTL file exists and its material (the first one used by ``usemtl``
    that has a ``map_Kd``, else the first ``map_Kd``) names an image pillow
    can read, the image becomes ``mesh.texture``; a missing MTL or image is
    not an error (``metadata["texture_warning"]`` says what was missing).
    The MTL and image must be relative paths to regular files inside the
    OBJ's folder (no absolute paths, ``..`` or links leading out; bounded
    sizes, see :mod:`geotex.io.limits`); a refused one is a warning too.

Writing
    Coordinates and texture coordinates use ``repr`` (shortest exact text),
    so a round trip is exact.  ``vt`` and ``v/vt`` corners are written when
    the mesh has uv.  When the mesh has a texture, ``NAME.mtl`` and
    ``NAME.png`` are written beside ``NAME.obj``; the three files appear
    together or not at all.
"""

from __future__ import annotations

import io
import os
import re
from pathlib import Path

import numpy as np

from geotex.errors import MeshFileError
from geotex.io._common import (build_mesh, decode_text, first_bad_number, format_rows,
                               line_starts, token_table, tokens_per_line, triangulate_polygons)
from geotex.io.images import load_texture_image, texture_to_png_bytes
from geotex.io.limits import MAX_SIDECAR_BYTES, RefusedInput, read_bounded, sidecar_file

__all__ = ["read_obj", "read_obj_colors", "write_obj"]

_CONTINUATION = re.compile(r"\\[ \t]*(?:\r\n|\n|\r)")
_KNOWN = frozenset("""v vt vn vp f fo l p o g s usemtl mtllib cstype deg bmat step curv curv2
    surf parm trim hole scrv sp end con mg bevel c_interp d_interp lod maplib usemap
    shadow_obj trace_obj ctech stech call csh""".split())
_MATERIAL_NAME = "geotex_texture"
# map_Kd options and how many arguments each takes (None: one to three numbers).
_MAP_OPTIONS = {"-blendu": 1, "-blendv": 1, "-bm": 1, "-boost": 1, "-cc": 1, "-clamp": 1,
                "-imfchan": 1, "-mm": 2, "-texres": 1, "-type": 1,
                "-o": None, "-s": None, "-t": None}


_WS = r"[ \t\f\v]"


def _statement(keyword: str) -> re.Pattern:
    """Rest of every line starting with ``keyword``, comment removed."""
    return re.compile(rf"^{_WS}*{keyword}(?![^\s]){_WS}*([^\n#]*)", re.MULTILINE)


_STATEMENTS = re.compile(
    rf"^{_WS}*(v|vt|f|mtllib|usemtl)(?![^\s]){_WS}*([^\n#]*)", re.MULTILINE)
_V = _statement("v")
_VT = _statement("vt")
_F = _statement("f")
_FIRST_WORD = re.compile(rf"^{_WS}*([^\s#]\S*)", re.MULTILINE)


class _Source:
    """The normalised OBJ text, with line lookups for error messages."""

    def __init__(self, path, text: str):
        self.path = path
        self.text = text
        self.kinds: list[str] = []

    def line_of(self, regex: re.Pattern, index: int) -> int:
        for i, match in enumerate(regex.finditer(self.text)):
            if i == index:
                return self.text.count("\n", 0, match.start()) + 1
        return self.text.count("\n") + 1

    def fail(self, regex: re.Pattern, index: int, message: str):
        raise MeshFileError(self.path, f"OBJ line {self.line_of(regex, index)}: {message}")


def read_obj(path, data: bytes):
    """Parse OBJ bytes into a :class:`~geotex.mesh.Mesh` (see module notes).

    Raises
    ------
    MeshFileError
        On a zero or out-of-range face index, a malformed number, or content
        that is not OBJ at all.
    """
    return _read_obj(path, data, colors=False)[0]


def read_obj_colors(path, data: bytes):
    """Parse OBJ bytes into a mesh and its per-vertex colours.

    Vertex colours are the common extension ``v x y z r g b`` (a seventh
    value, alpha, is ignored): read when every ``v`` line has at least six
    values, as 0..1 when no colour value exceeds 1, else as 0..255.

    Returns
    -------
    mesh : geotex.mesh.Mesh
    face_colors : None
        OBJ has no per-face colours (materials are not read as colours).
    vertex_colors : numpy.ndarray, (n, 3) float64 or None
        0..255.

    Raises
    ------
    MeshFileError
        As :func:`read_obj`, and for non-finite or negative colours.
    """
    return _read_obj(path, data, colors=True)


def _read_obj(path, data: bytes, *, colors: bool):
    text = decode_text(path, data, "OBJ")
    if "\r" in text:
        text = text.replace("\r\n", "\n").replace("\r", "\n")
    if "\\" in text:
        text = _CONTINUATION.sub(" ", text)
    src = _Source(path, text)
    statements = _STATEMENTS.findall(text)
    src.kinds = [k for k, _ in statements]
    v_rows = [r for k, r in statements if k == "v"]
    if not v_rows:
        for match in _FIRST_WORD.finditer(text):
            if match.group(1) not in _KNOWN:
                raise MeshFileError(
                    path, f"not an OBJ file: line {text.count(chr(10), 0, match.start()) + 1} "
                          f"starts with the unknown statement {match.group(1)[:40]!r} and "
                          "there are no 'v' vertex lines")
    V, rgb = _parse_vertices(src, v_rows, colors=colors)
    f_rows = [r for k, r in statements if k == "f"]
    vt_rows = [r for k, r in statements if k == "vt"] if f_rows else []
    faces, uv, uv_faces, skipped = _parse_faces(src, f_rows, V, vt_rows)
    meta = {}
    if skipped:
        meta["skipped_faces"] = skipped
    texture = None
    mtllibs = [r.strip() for k, r in statements if k == "mtllib" and r.strip()]
    if mtllibs and not colors:
        used = [r.strip() for k, r in statements if k == "usemtl" and r.strip()]
        texture, image, note = _find_texture(Path(str(path)), mtllibs, used)
        if note:
            meta["texture_warning"] = note
        if image is not None:
            meta["texture_file"] = str(image)
    mesh = build_mesh(path, V, faces, fmt="obj", uv=uv, uv_faces=uv_faces,
                      texture=texture, metadata=meta)
    return mesh, None, rgb


def _parse_vertices(src: _Source, rows: list[str], *, colors: bool = False):
    """Vertex positions (n, 3) and, with ``colors``, colours (n, 3) in 0..255 or None."""
    if not rows:
        return np.zeros((0, 3)), None
    counts, values, tokens = token_table(rows)
    short = np.flatnonzero(counts < 3)
    if short.size:
        i = int(short[0])
        src.fail(_V, i, f"vertex needs x y z, got {int(counts[i])} values")
    starts = line_starts(counts)
    rgb = None
    if colors and (counts >= 6).all():
        cols = starts[:, None] + np.arange(3, 6)
        if values is not None:
            rgb = values[cols]
        else:
            picked = [tokens[j] for j in cols.ravel().tolist()]
            try:
                rgb = np.array(picked, dtype=np.float64).reshape(-1, 3)
            except ValueError:
                row = next(j // 3 for j, t in enumerate(picked) if first_bad_number([t]) != "?")
                src.fail(_V, row, f"bad vertex colour {first_bad_number(picked)!r}")
        ok = (np.isfinite(rgb) & (rgb >= 0)).all(axis=1)
        if not ok.all():
            row = int(np.flatnonzero(~ok)[0])
            src.fail(_V, row, f"vertex colour {rgb[row].tolist()} is not a finite, "
                              "non-negative colour")
        rgb = rgb * 255.0 if rgb.max() <= 1.0 else rgb
    if values is not None:
        if (counts == 3).all():
            return values.reshape(-1, 3), rgb
        return values[starts[:, None] + np.arange(3)], rgb
    picked = [tokens[j] for j in (starts[:, None] + np.arange(3)).ravel().tolist()]
    try:
        return np.array(picked, dtype=np.float64).reshape(-1, 3), rgb
    except ValueError:
        row = next(j // 3 for j, t in enumerate(picked) if first_bad_number([t]) != "?")
        src.fail(_V, row, f"bad vertex coordinate {first_bad_number(picked)!r}")


def _parse_uv(src: _Source, rows: list[str]) -> np.ndarray:
    counts, values, tokens = token_table(rows)
    empty = np.flatnonzero(counts == 0)
    if empty.size:
        src.fail(_VT, int(empty[0]), "'vt' without values")
    starts = line_starts(counts)
    if values is None:
        for j, t in enumerate(tokens):
            if first_bad_number([t]) != "?":
                row = int(np.searchsorted(starts, j, side="right")) - 1
                src.fail(_VT, row, f"bad texture coordinate {t[:40]!r}")
    uv = np.zeros((len(rows), 2))
    uv[:, 0] = values[starts]
    has_v = counts >= 2
    uv[has_v, 1] = values[starts[has_v] + 1]
    return uv


def _corner_layout(block: str, n_corners: int):
    """``(slashes, double)`` shared by every corner token, or None if they differ."""
    raw = np.frombuffer(block.encode("utf-8", "surrogatepass"), dtype=np.uint8)
    space = raw <= 32
    start = ~space
    start[1:] &= space[:-1]
    token_starts = np.flatnonzero(start)
    if token_starts.shape[0] != n_corners:
        return None
    slash = raw == 47
    slashes = np.flatnonzero(slash)
    per_token = np.bincount(np.searchsorted(token_starts, slashes, side="right") - 1,
                            minlength=n_corners)
    if not (per_token == per_token[0]).all():
        return None
    double = np.flatnonzero(slash[1:] & slash[:-1])
    doubles = np.bincount(np.searchsorted(token_starts, double, side="right") - 1,
                          minlength=n_corners)
    if not (doubles == doubles[0]).all() or doubles[0] > 1:
        return None
    return int(per_token[0]), bool(doubles[0])


def _corner_indices(src: _Source, block: str, corners: list[str], counts: np.ndarray):
    """Raw (1-based / negative) vertex and texture indices of every corner."""
    n = len(corners)
    layout = _corner_layout(block, n) if "/" in block else (0, False)
    if layout is not None:
        slashes, double = layout
        width = slashes + 1 - int(double)
        fields = block.replace("/", " ").split() if slashes else corners
        if len(fields) == n * width:
            try:
                table = np.array(fields, dtype=np.int64).reshape(n, width)
            except (ValueError, OverflowError):
                table = None
            if table is not None:
                has_t = slashes >= 1 and not double
                return table[:, 0], (table[:, 1] if has_t else None)
    # General path: corners of mixed forms, or bad numbers to report.
    split = [c.split("/") for c in corners]
    v_raw = _ints(src, [s[0] for s in split], counts, "vertex index")
    if all(len(s) > 1 and s[1] for s in split):
        return v_raw, _ints(src, [s[1] for s in split], counts, "texture index")
    return v_raw, None


def _ints(src: _Source, strings: list[str], counts: np.ndarray, what: str) -> np.ndarray:
    try:
        return np.array(strings, dtype=np.int64)
    except (ValueError, OverflowError):
        ends = np.cumsum(counts)
        for i, s in enumerate(strings):
            try:
                int(s)
            except ValueError:
                face = int(np.searchsorted(ends, i, side="right"))
                src.fail(_F, face, f"bad {what} {s[:40]!r} in a face")
        raise MeshFileError(src.path, f"OBJ has a {what} too large to be real")


def _before(src: _Source, counts: np.ndarray):
    """Number of ``v`` and ``vt`` lines before each corner's face."""
    kinds = np.array([k for k in src.kinds if k in ("v", "vt", "f")])
    is_f = kinds == "f"
    v_before = np.cumsum(kinds == "v")[is_f]
    vt_before = np.cumsum(kinds == "vt")[is_f]
    return np.repeat(v_before, counts), np.repeat(vt_before, counts)


def _resolve(src: _Source, raw: np.ndarray, before, total: int, counts: np.ndarray,
             what: str) -> np.ndarray:
    """Turn 1-based / negative OBJ indices into 0-based ones, checking the range."""
    if before is None:
        idx = raw - 1
    else:
        idx = np.where(raw > 0, raw - 1, before + raw)
    bad = (raw == 0) | (idx < 0) | (idx >= total)
    if bad.any():
        corner = int(np.flatnonzero(bad)[0])
        face = int(np.searchsorted(np.cumsum(counts), corner, side="right"))
        value = int(raw[corner])
        if value == 0:
            msg = f"{what} index 0 is invalid (OBJ indices start at 1)"
        else:
            plural = "vertices" if what == "vertex" else "texture coordinates"
            msg = f"{what} index {value} is out of range (the file defines {total} {plural}"
            msg += f", {int(before[corner])} before this face)" if value < 0 else ")"
        src.fail(_F, face, f"face {msg}")
    return idx


def _parse_faces(src: _Source, rows: list[str], V: np.ndarray, vt_rows: list[str]):
    if not rows:
        return np.zeros((0, 3), dtype=np.int64), None, None, 0
    block = "\n".join(rows)
    corners = block.split()
    counts = tokens_per_line(block, len(rows))
    if counts is None or int(counts.sum()) != len(corners):
        counts = np.fromiter((len(r.split()) for r in rows), dtype=np.int64, count=len(rows))
    v_raw, t_raw = _corner_indices(src, block, corners, counts)
    v_before = t_before = None
    if (v_raw < 0).any() or (t_raw is not None and (t_raw < 0).any()):
        v_before, t_before = _before(src, counts)
    v_idx = _resolve(src, v_raw, v_before, V.shape[0], counts, "vertex")
    if t_raw is not None and vt_rows:
        uv = _parse_uv(src, vt_rows)
        t_idx = _resolve(src, t_raw, t_before, uv.shape[0], counts, "texture")
        tri, skipped = triangulate_polygons(counts, np.stack([v_idx, t_idx], axis=1), V)
        return tri[:, :, 0], uv, tri[:, :, 1], skipped
    tri, skipped = triangulate_polygons(counts, v_idx, V)
    return tri, None, None, skipped


def _mtl_candidates(obj_path: Path, mtllibs: list[str]) -> tuple[list[Path], str | None]:
    """MTL files to look at, and the first refusal (see :mod:`geotex.io.limits`)."""
    out, refused = [], None
    for lib in mtllibs:
        names = [lib] + (lib.split() if len(lib.split()) > 1 else [])
        for name in names:
            try:
                out.append(sidecar_file(obj_path, name, what="material library"))
            except RefusedInput as exc:
                refused = refused or str(exc)
    return out, refused


def _map_file(rest: str) -> str:
    """The file name of a ``map_Kd`` statement, options removed."""
    tokens = rest.split()
    i = 0
    while i < len(tokens) and tokens[i] in _MAP_OPTIONS:
        nargs = _MAP_OPTIONS[tokens[i]]
        i += 1
        if nargs is None:
            taken = 0
            while i < len(tokens) - 1 and taken < 3:
                try:
                    float(tokens[i])
                except ValueError:
                    break
                i += 1
                taken += 1
        else:
            i += nargs
    return " ".join(tokens[i:])


def _parse_mtl(text: str) -> list[tuple[str, str]]:
    """``(material, map_Kd file)`` pairs in file order."""
    maps = []
    current = ""
    for raw in text.splitlines():
        parts = raw.strip().split(None, 1)
        if len(parts) < 2:
            continue
        if parts[0] == "newmtl":
            current = parts[1].strip()
        elif parts[0].lower() == "map_kd":
            name = _map_file(parts[1])
            if name:
                maps.append((current, name))
    return maps


def _texture_source(obj_path: Path, mtllibs: list[str], used: list[str]):
    """Return ``(image path or None, warning or None)``."""
    mtl_files, refused = _mtl_candidates(obj_path, mtllibs)
    if not mtl_files:
        return None, refused or f"material library {mtllibs[0]!r} not found"
    maps = []
    for mtl in mtl_files:
        try:
            raw = read_bounded(mtl, MAX_SIDECAR_BYTES, what=f"material library {mtl.name!r}")
        except RefusedInput:
            continue
        text = raw.decode("utf-8", errors="replace")
        maps.extend((name, mtl, image) for name, image in _parse_mtl(text))
    if not maps:
        return None, None
    chosen = None
    for name in used:
        chosen = next((m for m in maps if m[0] == name), None)
        if chosen is not None:
            break
    chosen = chosen or maps[0]
    mtl_dir = chosen[1].parent.relative_to(Path(os.path.realpath(obj_path.parent)))
    reference = "/".join(list(mtl_dir.parts) + [chosen[2].replace("\\", "/")])
    try:
        image = sidecar_file(obj_path, reference, what="texture image")
    except RefusedInput as exc:
        return None, str(exc)
    return image, None


def _find_texture(obj_path: Path, mtllibs: list[str], used: list[str]):
    """Return ``(texture or None, image path or None, warning or None)``; never raises."""
    try:
        image, note = _texture_source(obj_path, mtllibs, used)
    except (OSError, ValueError) as exc:
        return None, None, f"material library unreadable: {exc}"
    if image is None:
        return None, None, note
    try:
        raw = read_bounded(image, MAX_SIDECAR_BYTES, what=f"texture image {image.name!r}")
        return load_texture_image(io.BytesIO(raw)), image, None
    except RefusedInput as exc:
        return None, None, str(exc)
    except Exception as exc:  # pillow raises many types for unreadable images
        return None, None, f"texture image {image.name!r} unreadable: {type(exc).__name__}"


def write_obj(group, path, mesh) -> None:
    """Write ``mesh`` as OBJ (plus MTL and PNG with a texture) through an atomic group.

    Parameters
    ----------
    group : geotex.io.atomic.AtomicGroup
        Opens the output files.
    path : pathlib.Path
        The ``.obj`` path; the MTL and PNG share its stem.
    mesh : geotex.mesh.Mesh
    """
    path = Path(path)
    V, F = mesh.vertices, mesh.faces
    head = [f"# geotex OBJ: {V.shape[0]} vertices, {F.shape[0]} triangles"]
    textured = mesh.texture is not None
    if textured:
        mtl_name = path.stem + ".mtl"
        png_name = path.stem + ".png"
        if path.name in (mtl_name, png_name):
            raise MeshFileError(path, "a textured OBJ needs its own name beside NAME.mtl "
                                      "and NAME.png; use the .obj extension")
        head.append(f"mtllib {mtl_name}")
    name = " ".join((mesh.name or path.stem).split())
    if name:
        head.append(f"o {name}")
    chunks = ["\n".join(head) + "\n", format_rows("v %r %r %r\n", V)]
    if mesh.uv is not None:
        chunks.append(format_rows("vt %r %r\n", mesh.uv))
    if textured:
        chunks.append(f"usemtl {_MATERIAL_NAME}\n")
    if mesh.uv is not None:
        corners = np.empty((F.shape[0], 6), dtype=np.int64)
        corners[:, 0::2] = F + 1
        corners[:, 1::2] = mesh.uv_faces + 1
        chunks.append(format_rows("f %d/%d %d/%d %d/%d\n", corners))
    else:
        chunks.append(format_rows("f %d %d %d\n", F + 1))
    group.open(path, "wb").write("".join(chunks).encode("utf-8"))
    if textured:
        mtl = (f"# geotex material\nnewmtl {_MATERIAL_NAME}\nKa 1 1 1\nKd 1 1 1\n"
               f"Ks 0 0 0\nd 1\nillum 1\nmap_Kd {png_name}\n")
        group.open(path.with_name(mtl_name), "wb").write(mtl.encode("utf-8"))
        group.open(path.with_name(png_name), "wb").write(texture_to_png_bytes(mesh.texture))

