"""Record files: named arrays plus a JSON metadata string in one ``.npz`` archive.

Shells, tile sets, direction fields, height-and-tilt textures, exemplars and
lapped-texture paste records are all stored this way.  :func:`read_record`
is their one reader: a missing file, a zip bomb (:func:`~geotex.io.limits.check_archive`),
a damaged archive, a missing array, invalid JSON and a wrong format tag each
give one :class:`~geotex.errors.MeshFileError` line naming the file, what kind
of record was expected and what to do (``hint``); arrays are never unpickled.
:func:`write_record` is the one writer (atomic; optionally byte-reproducible).
"""

from __future__ import annotations

import io
import json
import zipfile
import zlib
from pathlib import Path

import numpy as np

from geotex.errors import InputError, MeshFileError, MissingFileError
from geotex.io.atomic import atomic_output
from geotex.io.limits import RefusedInput, check_archive

__all__ = ["read_record", "write_record"]

#: what a damaged archive raises while its members are read
_UNREADABLE = (OSError, ValueError, TypeError, EOFError, KeyError, zipfile.BadZipFile,
               zlib.error, UnicodeDecodeError)


def read_record(path, *, kind: str, format: str, arrays, optional=(),
                metadata_key: str = "metadata", record: str | None = None,
                hint: str = "") -> tuple[dict, dict]:
    """Read the arrays and the JSON metadata of a record file.

    Parameters
    ----------
    path : str or os.PathLike
    kind : str
        What the file holds, in messages: ``"no such {kind} file"``,
        ``"unreadable {kind} file"``.
    format : str
        The tag ``metadata["format"]`` must equal.
    arrays : sequence of str, or callable
        Names of the arrays the file must hold (besides the metadata); a
        callable receives the metadata dict and returns the names (for
        records whose array names depend on it).
    optional : sequence of str
        Arrays returned when present.
    metadata_key : str
        Name of the member holding the JSON string (a numpy string scalar,
        or UTF-8 bytes as ``uint8``).
    record : str, optional
        What a valid file is, in "not a {record}" messages (default
        ``"geotex {kind}"``).
    hint : str
        What to do, appended to every message (e.g. "rebuild it with 'geotex
        shell build'").

    Returns
    -------
    arrays : dict of str -> numpy.ndarray
        The required arrays and the optional ones present.
    metadata : dict

    Raises
    ------
    MissingFileError
        If ``path`` is not a file.
    MeshFileError
        If the archive would inflate too far, is damaged or truncated, lacks
        an array, its metadata is not a JSON object, or its format tag is not
        ``format``.
    """
    path = Path(path)
    record = record or f"geotex {kind}"
    tail = f"; {hint}" if hint else ""
    if not path.is_file():
        raise MissingFileError(f"{path}: no such {kind} file")
    if not zipfile.is_zipfile(path):
        raise MeshFileError(path, f"unreadable {kind} file (not an .npz archive): damaged "
                                  f"or not a {kind} file (truncated or corrupted?){tail}")
    try:
        check_archive(path)
    except RefusedInput as exc:
        raise MeshFileError(path, str(exc)) from None
    try:
        with np.load(path, allow_pickle=False) as z:
            if metadata_key not in z.files:
                raise MeshFileError(path, f"not a {record}: missing array "
                                          f"'{metadata_key}'{tail}")
            meta = _json_of(z[metadata_key], path, kind, tail)
            if not isinstance(meta, dict) or meta.get("format") != format:
                found = meta.get("format") if isinstance(meta, dict) else None
                raise MeshFileError(path, f"not a {record} (format {found!r}, expected "
                                          f"{format!r}){tail}")
            names = list(arrays(meta) if callable(arrays) else arrays)
            missing = [k for k in names if k not in z.files]
            if missing:
                raise MeshFileError(path, f"not a {record}: missing array"
                                          f"{'s' if len(missing) > 1 else ''} "
                                          f"{', '.join(map(repr, missing))}{tail}")
            data = {k: z[k] for k in names + [k for k in optional if k in z.files]}
    except MeshFileError:
        raise
    except _UNREADABLE as exc:
        raise MeshFileError(path, f"unreadable {kind} file ({type(exc).__name__}: {exc}): "
                                  f"damaged or not a {kind} file (truncated or "
                                  f"corrupted?){tail}") from None
    return data, meta


def _json_of(member: np.ndarray, path: Path, kind: str, tail: str):
    text = (bytes(member).decode("utf-8") if member.dtype == np.uint8 else str(member))
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise MeshFileError(path, f"{kind} metadata is not valid JSON ({exc}){tail}") from None


def write_record(path, arrays: dict, *, compressed: bool, date_time=None,
                 kind: str | None = None) -> Path:
    """Write ``arrays`` (name -> array, in member order) as an ``.npz`` archive, atomically.

    Parameters
    ----------
    path : str or os.PathLike
    arrays : dict of str -> array_like
        Written in this order, with these dtypes, never pickled.
    compressed : bool
        Deflate the members (:func:`numpy.savez_compressed`) or store them
        (:func:`numpy.savez`).
    date_time : tuple of 6 int, optional
        A fixed member time stamp: the archive is then written member by
        member at deflate level 9 with fixed attributes, so the same arrays
        always give the same bytes (requires ``compressed``).  Without it,
        numpy's writer (time stamps of now).
    kind : str, optional
        When given, a path not ending in ``.npz`` is refused with a message
        naming ``kind``.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    InputError
        If ``kind`` is given and the path does not end in ``.npz``.
    MeshFileError
        If the file cannot be written (nothing is left behind).
    """
    path = Path(path)
    if kind is not None and path.suffix.lower() != ".npz":
        raise InputError(f"{path}: {kind} files are .npz; use a .npz file name")
    buf = io.BytesIO()
    if date_time is None:
        (np.savez_compressed if compressed else np.savez)(buf, **arrays)
    else:
        if not compressed:
            raise InputError("write_record: date_time needs compressed=True")
        with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
            for key, arr in arrays.items():
                member = io.BytesIO()
                np.lib.format.write_array(member, np.asarray(arr), allow_pickle=False)
                info = zipfile.ZipInfo(f"{key}.npy", date_time=tuple(date_time))
                info.compress_type = zipfile.ZIP_DEFLATED
                info.external_attr = 0o644 << 16
                zf.writestr(info, member.getvalue(), compresslevel=9)
    with atomic_output(path, "wb") as fh:
        fh.write(buf.getvalue())
    return path
