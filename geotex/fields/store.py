"""Field files: a direction field saved as ``.npz`` with JSON metadata."""

from __future__ import annotations

import json
from dataclasses import dataclass, field as dc_field
from pathlib import Path

import numpy as np

from geotex.errors import MeshFileError
from geotex.fields.directions import DirectionField
from geotex.io.records import read_record, write_record

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
    sing = np.asarray(field.singularities, dtype=np.float64).reshape(-1, 2)
    meta = {"format": FIELD_FORMAT, "symmetry": int(field.symmetry), **(metadata or {})}
    arrays = dict(vectors=field.vectors, values=field.values, normals=field.normals,
                  constrained=field.constrained, singular_vertices=sing[:, 0].astype(np.int64),
                  singular_indices=sing[:, 1], metadata=np.array(json.dumps(meta)))
    if scale is not None:
        arrays["scale"] = np.asarray(scale, dtype=np.float64)
    return write_record(path, arrays, compressed=True, kind="field")


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
    path = Path(path)
    data, meta = read_record(path, kind="field", record="geotex direction field",
                             format=FIELD_FORMAT, optional=("scale",),
                             arrays=("vectors", "values", "normals", "constrained",
                                     "singular_vertices", "singular_indices"),
                             hint="write one with 'geotex field'")
    try:
        sing = tuple((int(v), float(k)) for v, k in
                     zip(data["singular_vertices"], data["singular_indices"]))
        field = DirectionField(vectors=data["vectors"], symmetry=int(meta["symmetry"]),
                               values=data["values"], singularities=sing,
                               normals=data["normals"], constrained=data["constrained"])
    except (ValueError, KeyError, TypeError) as exc:
        raise MeshFileError(path, f"damaged or not a field file ({type(exc).__name__}: "
                                  f"inconsistent arrays or metadata)") from None
    return FieldFile(field=field, scale=data.get("scale"), metadata=meta)
