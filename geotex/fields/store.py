"""Field files: a direction field saved as ``.npz`` with JSON metadata."""

from __future__ import annotations

import io
import json
import zipfile
from dataclasses import dataclass, field as dc_field
from pathlib import Path

import numpy as np

from geotex.errors import InputError, MeshFileError, MissingFileError
from geotex.io.limits import RefusedInput, check_archive

__all__ = ["save_direction_field", "load_direction_field", "FieldFile", "FIELD_FORMAT"]

#: Format tag stored in every field file.
FIELD_FORMAT = "geotex-direction-field/1"


@dataclass
class FieldFile:
    """Contents of a field file.

    Attributes
    ----------
    field : DirectionField
    scale : numpy.ndarray, (n,) float64, or None
        Per-vertex texture scale, when one was saved.
    metadata : dict
    """

    field: object
    scale: np.ndarray | None = None
    metadata: dict = dc_field(default_factory=dict)


def save_direction_field(path, field, *, scale=None, metadata: dict | None = None) -> Path:
    """Write a :class:`~geotex.fields.directions.DirectionField` to ``path`` (.npz).

    The file holds ``vectors`` (m, 3), ``values`` (m,) complex, ``normals``
    (m, 3), ``constrained`` (k,), ``singular_vertices`` (s,) int64,
    ``singular_indices`` (s,) float64, optionally ``scale`` (n,) float64, and
    ``metadata`` (a JSON string with ``format``, ``symmetry`` and the caller's
    entries).  Written atomically.

    Returns
    -------
    pathlib.Path
    """
    from geotex.io.atomic import atomic_output

    path = Path(path)
    if path.suffix.lower() != ".npz":
        raise InputError(f"{path}: field files are .npz; use a .npz file name")
    sing = np.asarray(field.singularities, dtype=np.float64).reshape(-1, 2)
    meta = {"format": FIELD_FORMAT, "symmetry": int(field.symmetry), **(metadata or {})}
    arrays = dict(vectors=field.vectors, values=field.values, normals=field.normals,
                  constrained=field.constrained, singular_vertices=sing[:, 0].astype(np.int64),
                  singular_indices=sing[:, 1], metadata=np.array(json.dumps(meta)))
    if scale is not None:
        arrays["scale"] = np.asarray(scale, dtype=np.float64)
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    with atomic_output(path, "wb") as fh:
        fh.write(buf.getvalue())
    return path


def load_direction_field(path) -> FieldFile:
    """Read a field file written by :func:`save_direction_field`.

    Returns
    -------
    FieldFile

    Raises
    ------
    MissingFileError
        If the file does not exist.
    MeshFileError
        If it is not a geotex field file or is damaged.
    """
    from geotex.fields.directions import DirectionField

    path = Path(path)
    if not path.is_file():
        raise MissingFileError(f"{path}: no such file")
    try:
        check_archive(path)
    except RefusedInput as exc:
        raise MeshFileError(path, str(exc)) from None
    try:
        with np.load(path, allow_pickle=False) as data:
            meta = json.loads(str(data["metadata"]))
            if meta.get("format") != FIELD_FORMAT:
                raise MeshFileError(path, f"not a geotex direction field (format "
                                          f"{meta.get('format')!r})")
            sing = tuple((int(v), float(k)) for v, k in
                         zip(data["singular_vertices"], data["singular_indices"]))
            field = DirectionField(vectors=data["vectors"], symmetry=int(meta["symmetry"]),
                                   values=data["values"], singularities=sing,
                                   normals=data["normals"], constrained=data["constrained"])
            scale = data["scale"] if "scale" in data.files else None
    except MeshFileError:
        raise
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, json.JSONDecodeError) as exc:
        raise MeshFileError(path, f"damaged or not a field file ({type(exc).__name__})") from None
    return FieldFile(field=field, scale=scale, metadata=meta)
