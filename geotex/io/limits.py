"""Input limits: what a mesh file may make geotex read, inflate or allocate.

A mesh file is untrusted input.  Readers follow these rules so that a small
hostile file cannot read other files on the machine, exhaust memory or run
for minutes:

* Files a mesh refers to (GLB buffer and image ``uri``, OBJ ``mtllib`` and
  ``map_Kd``) must be relative references that resolve, symlinks followed,
  to a regular file inside the folder of the mesh file itself: absolute
  paths, ``..`` components, URI schemes other than ``data:`` and links that
  leave the folder are refused (:func:`sidecar_file`).  They are read with a
  bound: the size the referring document declares, else
  :data:`MAX_SIDECAR_BYTES` (:func:`read_bounded`).
* Compressed parts (3MF zip entries) are inflated in a streaming way, never
  beyond their declared size nor beyond :data:`MAX_INFLATED_BYTES`, and a
  part whose compression ratio is beyond :data:`MAX_INFLATE_RATIO` is
  refused before inflating it (:func:`inflate_member`).
* Texture images larger than :data:`MAX_TEXTURE_PIXELS` are refused before
  their pixels are decoded.
* Element counts in headers are checked against the bytes actually present
  before anything is allocated (in each format module).

Every refusal is a one-line message saying what was refused and why.
"""

from __future__ import annotations

import os
import re
import stat
from pathlib import Path
from urllib.parse import unquote

from geotex.errors import InputError

__all__ = ["MAX_SIDECAR_BYTES", "MAX_INFLATED_BYTES", "MAX_INFLATE_RATIO",
           "MAX_TEXTURE_PIXELS", "RefusedInput", "sidecar_file", "read_bounded",
           "inflate_member", "check_archive", "human_bytes"]

#: Largest file a mesh may refer to (MTL, texture image, GLB buffer), in bytes.
MAX_SIDECAR_BYTES = 1 << 30
#: Largest size a compressed part may inflate to, in bytes.
MAX_INFLATED_BYTES = 1 << 30
#: Largest inflated / compressed size ratio accepted for parts above 1 MiB
#: (XML meshes compress 3-20 times; deflate cannot exceed about 1032).
MAX_INFLATE_RATIO = 200
#: Largest texture image, in pixels (8192 x 8192).
MAX_TEXTURE_PIXELS = 8192 * 8192

_SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")


class RefusedInput(InputError):
    """A reference or a part a mesh file asks for is refused (message says why)."""


def human_bytes(n: int) -> str:
    """``1536`` -> ``'1.5 KiB'``."""
    value = float(n)
    for unit in ("bytes", "KiB", "MiB", "GiB", "TiB"):
        if value < 1024 or unit == "TiB":
            return f"{int(value)} bytes" if unit == "bytes" else f"{value:.1f} {unit}"
        value /= 1024
    return f"{n} bytes"  # pragma: no cover


def sidecar_file(mesh_path, reference: str, *, what: str, uri: bool = False) -> Path:
    """Resolve a file reference found inside a mesh file, or refuse it.

    Parameters
    ----------
    mesh_path : str or os.PathLike
        The mesh file holding the reference; its folder is the only place
        referenced files may come from.
    reference : str
        The reference as written (relative path, or URI when ``uri``).
    what : str
        What the reference is, for messages (``"buffers[0] uri"``).
    uri : bool, optional
        Percent-decode the reference first (glTF URIs are URI-encoded).

    Returns
    -------
    pathlib.Path
        The resolved path of an existing regular file inside the folder.

    Raises
    ------
    RefusedInput
        If the reference is absolute, has a scheme or ``..``, leaves the
        folder (symlinks included), does not exist or is not a regular file.
    """
    text = str(reference)
    shown = text if len(text) <= 60 else text[:57] + "..."
    if uri:
        if _SCHEME.match(text) and not re.match(r"^[A-Za-z]:[\\/]", text):
            raise RefusedInput(f"{what} {shown!r} is refused: only relative file "
                               "references and data: URIs are allowed")
        text = unquote(text)
    text = text.replace("\\", "/")
    if "\x00" in text or not text.strip():
        raise RefusedInput(f"{what} {shown!r} is not a valid file name")
    if text.startswith("/") or re.match(r"^[A-Za-z]:", text):
        raise RefusedInput(f"{what} {shown!r} is refused: absolute paths are not "
                           "allowed; put the file next to the mesh and refer to it by name")
    parts = [p for p in text.split("/") if p not in ("", ".")]
    if ".." in parts:
        raise RefusedInput(f"{what} {shown!r} is refused: '..' leaves the folder of "
                           "the mesh file")
    folder = Path(os.path.realpath(Path(str(mesh_path)).parent))
    target = Path(os.path.realpath(folder.joinpath(*parts)))
    if target != folder and folder not in target.parents:
        raise RefusedInput(f"{what} {shown!r} is refused: it is a link to a file "
                           "outside the folder of the mesh file")
    try:
        st = target.stat()
    except OSError:
        raise RefusedInput(f"{what} {shown!r} not found next to the mesh file") from None
    if not stat.S_ISREG(st.st_mode):
        raise RefusedInput(f"{what} {shown!r} is not a regular file")
    return target


def read_bounded(path: Path, limit: int, *, what: str, exact: bool = False) -> bytes:
    """Read at most ``limit`` bytes of a regular file.

    Parameters
    ----------
    exact : bool, optional
        ``limit`` is the size the referring document declares: read the first
        ``limit`` bytes (a shorter file is an error).  Otherwise a file larger
        than ``limit`` is refused.

    Raises
    ------
    RefusedInput
        If the file is too large (or too short with ``exact``), not regular,
        or unreadable.
    """
    try:
        fd = os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise RefusedInput(f"{what} cannot be read: {exc.strerror or exc}") from None
    with os.fdopen(fd, "rb") as fh:
        st = os.fstat(fh.fileno())
        if not stat.S_ISREG(st.st_mode):
            raise RefusedInput(f"{what} is not a regular file")
        if exact:
            if st.st_size < limit:
                raise RefusedInput(f"{what} has {st.st_size} bytes, fewer than the "
                                   f"{limit} declared")
        elif st.st_size > limit:
            raise RefusedInput(f"{what} is {human_bytes(st.st_size)}, more than the "
                               f"{human_bytes(limit)} allowed")
        data = fh.read(limit if exact else st.st_size)   # never a buffer beyond the file
    if exact and len(data) < limit:
        raise RefusedInput(f"{what} has {len(data)} bytes, fewer than the {limit} declared")
    return data


def inflate_member(archive, name: str, *, cap: int = MAX_INFLATED_BYTES,
                   ratio: int = MAX_INFLATE_RATIO) -> bytes:
    """Inflate one zip member with bounds (streaming; never beyond the limits).

    Parameters
    ----------
    archive : zipfile.ZipFile
    name : str
        Member name (``KeyError`` if absent, as :meth:`zipfile.ZipFile.read`).
    cap : int, optional
        Absolute limit on the inflated size.
    ratio : int, optional
        Limit on inflated / compressed size for members above 1 MiB.

    Raises
    ------
    KeyError
        If there is no such member.
    RefusedInput
        If the declared size exceeds ``cap`` or the ratio, or the data inflate
        to more than declared.
    zipfile.BadZipFile, zlib.error, EOFError, ...
        On damaged data, as :mod:`zipfile` raises them.
    """
    info = archive.getinfo(name)
    declared = int(info.file_size)
    packed = max(int(info.compress_size), 1)
    if declared > cap:
        raise RefusedInput(f"part {name!r} inflates to {human_bytes(declared)}, more than "
                           f"the {human_bytes(cap)} allowed (zip bomb?)")
    if declared > (1 << 20) and declared > ratio * packed:
        raise RefusedInput(f"part {name!r} inflates {declared // packed} times "
                           f"({human_bytes(packed)} to {human_bytes(declared)}), more "
                           f"than the {ratio} times a mesh compresses (zip bomb?)")
    # the declared size is bounded above; zipfile never inflates beyond it
    # (a member that holds more fails its CRC check), so one read is enough
    with archive.open(info) as fh:
        out = fh.read(declared + 1)
        if len(out) > declared or fh.read(1):
            raise RefusedInput(f"part {name!r} inflates to more than the "
                               f"{declared} bytes it declares (damaged or hostile)")
    return out


def check_archive(source, *, cap: int = MAX_INFLATED_BYTES,
                  ratio: int = MAX_INFLATE_RATIO) -> None:
    """Refuse a zip archive (``.npz``, ``.3mf``) whose members would inflate too far.

    Reads only the central directory: call it before :func:`numpy.load`,
    which inflates members itself.  A file that is not a zip archive passes
    (the loader reports it).

    Raises
    ------
    RefusedInput
        If a member declares more than ``cap`` bytes, more than ``ratio``
        times its compressed size (above 1 MiB), or the members together
        more than ``cap``.
    """
    import zipfile

    try:
        with zipfile.ZipFile(source) as archive:
            infos = archive.infolist()
    except (zipfile.BadZipFile, OSError, ValueError, EOFError):
        return
    total = 0
    for info in infos:
        declared, packed = int(info.file_size), max(int(info.compress_size), 1)
        total += declared
        if declared > cap or total > cap:
            raise RefusedInput(f"archive member {info.filename!r} inflates to "
                               f"{human_bytes(declared)}, beyond the {human_bytes(cap)} "
                               "allowed (zip bomb?)")
        if declared > (1 << 20) and declared > ratio * packed:
            raise RefusedInput(f"archive member {info.filename!r} inflates "
                               f"{declared // packed} times, more than the {ratio} times "
                               "allowed (zip bomb?)")
