"""Mesh file reading and writing: STL, OBJ, PLY, OFF, 3MF and GLB.

>>> import pathlib, tempfile
>>> from geotex.data import sample_path
>>> from geotex.io import read_mesh, write_mesh
>>> mesh = read_mesh(sample_path("spot"))              # a bundled OBJ
>>> tmp = tempfile.TemporaryDirectory()
>>> out = write_mesh(pathlib.Path(tmp.name) / "spot.3mf", mesh)
>>> read_mesh(out).n_faces == mesh.n_faces
True
>>> tmp.cleanup()

The format comes from the file extension (case-insensitive) or the
``format=`` argument; a file is never silently parsed as another format.
When parsing fails and the content looks like another supported format, the
error says so ("content looks like a binary STL file; rename it with the .stl
extension").

Reading returns a :class:`geotex.mesh.Mesh` with ``metadata["format"]`` and
``metadata["source"]`` set (colours are dropped; :func:`read_mesh_colors`
returns the per-face and per-vertex colours of PLY and OBJ files too); see
each format module for what is read:

=======  ===============================================================
.stl     :mod:`geotex.io.stl`: ASCII and binary; corners welded exactly
.obj     :mod:`geotex.io.obj`: uv, n-gons, MTL ``map_Kd`` texture
.ply     :mod:`geotex.io.ply`: ASCII, binary little / big endian
.off     :mod:`geotex.io.off`: OFF and its COFF / NOFF variants
.3mf     :mod:`geotex.io.threemf`: build items, components, units -> mm
.glb     :mod:`geotex.io.glb`: binary glTF 2.0 with embedded texture
=======  ===============================================================

Every failure caused by the file is a :class:`~geotex.errors.GeotexError`:
:class:`~geotex.errors.MissingFileError`,
:class:`~geotex.errors.UnsupportedFormatError` or
:class:`~geotex.errors.MeshFileError` (truncated, malformed, non-finite
coordinates, out-of-range indices...), each with a one-line message naming
the file.  Files are untrusted input: what they may make geotex read, inflate
or allocate is bounded (:mod:`geotex.io.limits`).  Writing is atomic (see
:mod:`geotex.io.atomic`).
"""

from __future__ import annotations

from pathlib import Path

from geotex.errors import (GeotexError, InputError, MeshFileError, MissingFileError,
                           UnsupportedFormatError)
from geotex.io._common import gc_paused, weld_exact
from geotex.io.atomic import atomic_group, atomic_output
from geotex.io.glb import read_glb, write_glb
from geotex.io.obj import read_obj, read_obj_colors, write_obj
from geotex.io.off import read_off, write_off
from geotex.io.ply import read_ply, read_ply_colors, write_ply
from geotex.io.sniff import mismatch_hint, sniff_format
from geotex.io.stl import read_stl, write_stl
from geotex.io.threemf import read_3mf, write_3mf
from geotex.mesh.record import Mesh

__all__ = ["read_mesh", "read_mesh_colors", "write_mesh", "weld_exact", "READ_FORMATS",
           "WRITE_FORMATS",
           "atomic_output", "atomic_group", "sniff_format", "format_of"]

READ_FORMATS = (".stl", ".obj", ".ply", ".off", ".3mf", ".glb")
WRITE_FORMATS = (".stl", ".obj", ".ply", ".off", ".3mf", ".glb")

_READERS = {"stl": read_stl, "obj": read_obj, "ply": read_ply, "off": read_off,
            "3mf": read_3mf, "glb": read_glb}
_COLOR_READERS = {"ply": read_ply_colors, "obj": read_obj_colors}
_WRITERS = {"stl": write_stl, "ply": write_ply, "off": write_off, "3mf": write_3mf,
            "glb": write_glb}
_NAMES = {"stl": "STL", "obj": "OBJ", "ply": "PLY", "off": "OFF", "3mf": "3MF",
          "glb": "GLB"}


def format_of(path, format: str | None = None, *, writing: bool = False) -> str:
    """Return the format key (``"stl"``, ``"obj"``, ...) for ``path``.

    Parameters
    ----------
    path : str or os.PathLike
    format : str, optional
        Explicit format name or extension (``"stl"``, ``".STL"``); overrides
        the extension of ``path``.
    writing : bool, optional
        Check against :data:`WRITE_FORMATS` instead of :data:`READ_FORMATS`.

    Raises
    ------
    UnsupportedFormatError
        If the extension or ``format`` is not supported.
    """
    supported = WRITE_FORMATS if writing else READ_FORMATS
    listing = ", ".join(supported)
    if format is not None:
        key = str(format).lower().lstrip(".")
        if "." + key not in supported:
            raise UnsupportedFormatError(
                path, f"unsupported format {format!r}; supported: {listing}")
        return key
    suffix = Path(str(path)).suffix.lower()
    if not suffix:
        raise UnsupportedFormatError(
            path, f"no file extension to tell the mesh format; use one of {listing}")
    if suffix not in supported:
        raise UnsupportedFormatError(
            path, f"unsupported extension {suffix!r}; supported: {listing}")
    return suffix[1:]


def read_mesh(path, *, format: str | None = None) -> Mesh:
    """Read a triangle mesh file.

    Parameters
    ----------
    path : str or os.PathLike
        A ``.stl``, ``.obj``, ``.ply``, ``.off``, ``.3mf`` or ``.glb`` file
        (extension case-insensitive).
    format : str, optional
        Read as this format (``"stl"``, ``"obj"``, ...) whatever the extension.

    Returns
    -------
    geotex.mesh.Mesh
        Vertices (float64, millimetres for 3MF), triangles (polygons are
        split without overlaps, concave ones included), optional uv / texture;
        ``name`` is the file stem.
        A file with vertices but no faces gives a mesh with no faces.

    Raises
    ------
    MissingFileError
        If ``path`` does not exist or is not a regular file.
    UnsupportedFormatError
        If the extension or ``format`` is not supported.
    MeshFileError
        If the file is empty, unreadable, truncated or malformed, holds
        non-finite coordinates or out-of-range indices, or breaks an input
        limit (:mod:`geotex.io.limits`: references outside its folder, zip
        bombs, absurd counts, polygons too tangled to triangulate).

    Examples
    --------
    >>> from geotex.data import sample_path
    >>> mesh = read_mesh(sample_path("spot"))
    >>> mesh.n_vertices, mesh.n_faces
    (829, 1654)
    """
    return _read(path, format, _READERS)


def read_mesh_colors(path, *, format: str | None = None):
    """Read a triangle mesh with its per-face and per-vertex colours (PLY, OBJ).

    PLY: ``red green blue`` (or ``r g b``, ``diffuse_*``) properties of the
    ``face`` and ``vertex`` elements, ASCII or binary, integer (0..255) or
    float (0..1) types (:func:`geotex.io.ply.read_ply_colors`).  OBJ: the
    ``v x y z r g b`` extension (:func:`geotex.io.obj.read_obj_colors`).

    Parameters
    ----------
    path : str or os.PathLike
        A ``.ply`` or ``.obj`` file.
    format : str, optional
        ``"ply"`` or ``"obj"`` whatever the extension.

    Returns
    -------
    mesh : geotex.mesh.Mesh
        As :func:`read_mesh` reads it (same faces in the same order).
    face_colors : numpy.ndarray, (m, 3) float64 or None
        Per triangle (a polygon's colour on each of its triangles), 0..255.
    vertex_colors : numpy.ndarray, (n, 3) float64 or None
        0..255.

    Raises
    ------
    MissingFileError, MeshFileError
        As :func:`read_mesh`; also non-finite or negative colours.
    UnsupportedFormatError
        A format other than PLY or OBJ (the other readers hold no colours).
    """
    key = format_of(path, format)
    if key not in _COLOR_READERS:
        raise UnsupportedFormatError(
            path, f"colours are read from PLY and OBJ files only, not {_NAMES[key]}")
    return _read(path, key, _COLOR_READERS)


def _read(path, format, readers):
    """``readers[key](path, data)`` with read_mesh's checks and one-line errors."""
    path = Path(path)
    if not path.exists():
        raise MissingFileError(f"{path}: no such file")
    if not path.is_file():
        kind = "a directory" if path.is_dir() else "not a regular file"
        raise MissingFileError(f"{path}: no such file ({kind})")
    try:
        key = format_of(path, format)
    except UnsupportedFormatError as exc:
        hint = _hint_for(path, None)
        if hint is None:
            raise
        raise UnsupportedFormatError(path, f"{exc.reason}; {hint}") from None
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise MeshFileError(path, f"cannot read: {exc.strerror or exc}") from None
    if not data:
        raise MeshFileError(path, "file is empty")
    try:
        with gc_paused():
            return readers[key](path, data)
    except MemoryError:
        raise
    except GeotexError as exc:
        error = exc
    except Exception as exc:  # any parser failure on bad content becomes a MeshFileError
        detail = " ".join(f"{type(exc).__name__}: {exc}".split())[:200]
        error = MeshFileError(path, f"malformed {_NAMES[key]} file ({detail})")
        error.__cause__ = exc
    hint = mismatch_hint(data, key)
    if hint is not None:
        reason = error.reason if isinstance(error, MeshFileError) else str(error)
        raise MeshFileError(path, f"{reason}; {hint}") from error
    if not isinstance(error, MeshFileError) and isinstance(error, InputError):
        raise MeshFileError(path, str(error)) from error
    raise error


def _hint_for(path: Path, expected):
    """Sniff hint from the first 64 KiB of ``path`` (and its size)."""
    try:
        with path.open("rb") as fh:
            head = fh.read(65536)
        size = path.stat().st_size
    except OSError:
        return None
    return mismatch_hint(head, expected or "", size=size)


def write_mesh(path, mesh, *, format: str | None = None, binary: bool = True) -> Path:
    """Write a mesh file atomically.

    Parameters
    ----------
    path : str or os.PathLike
        Destination; the extension picks the format unless ``format`` is given.
    mesh : geotex.mesh.Mesh
    format : str, optional
        ``"stl"``, ``"obj"``, ``"ply"``, ``"off"``, ``"3mf"`` or ``"glb"``.
    binary : bool, optional
        Binary or ASCII encoding for STL and PLY; ignored by the other
        formats (OBJ and OFF are text, 3MF and GLB binary).

    Returns
    -------
    pathlib.Path
        The path written.  An OBJ of a textured mesh also writes ``NAME.mtl``
        and ``NAME.png`` beside it.

    Raises
    ------
    InputError
        If ``mesh`` is not a :class:`~geotex.mesh.Mesh`.
    UnsupportedFormatError
        If the extension or ``format`` is not supported (nothing is written).
    MeshFileError
        If the directory does not exist, the file cannot be written, or the
        coordinates do not fit the format (float32 range of binary STL / GLB).

    Notes
    -----
    Data goes to a temporary file in the destination directory, renamed over
    ``path`` only when complete: on any error no file (and no temporary file)
    is left and an existing file at ``path`` is unchanged.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from geotex.mesh import Mesh
    >>> from geotex.mesh.primitives import icosphere
    >>> tmp = tempfile.TemporaryDirectory()
    >>> write_mesh(pathlib.Path(tmp.name) / "ball.3mf", Mesh(*icosphere(2))).name
    'ball.3mf'
    >>> tmp.cleanup()
    """
    if not isinstance(mesh, Mesh):
        raise InputError(f"mesh must be a geotex.mesh.Mesh, got {type(mesh).__name__}")
    path = Path(path)
    key = format_of(path, format, writing=True)
    if key == "obj":
        with atomic_group() as group:
            write_obj(group, path, mesh)
        return path
    with atomic_output(path, "wb") as fh:
        _WRITERS[key](fh, mesh, path=path, binary=binary)
    return path
