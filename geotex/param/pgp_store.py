"""PGP files: the per-corner tile coordinates of :func:`geotex.param.pgp.periodic_parameterization`.

An ``.npz`` archive (written by ``geotex pgp``) with ``coords`` (m, 3, 2),
``singular`` (m,), ``scale`` (n,), ``cone_vertices``, ``cone_indices``,
``functions`` (n, 4) and ``axes`` (m, 3) (what a local update starts from)
and a JSON ``metadata`` string whose ``format`` is :data:`PGP_FORMAT`.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from geotex.errors import MeshFileError
from geotex.io.records import read_record, write_record

__all__ = ["PGP_FORMAT", "PgpFile", "save_parameterization", "load_parameterization"]

#: Format tag stored in every PGP file.
PGP_FORMAT = "geotex-pgp/1"


@dataclass(frozen=True)
class PgpFile:
    """The contents of a PGP file.

    Attributes
    ----------
    coords : numpy.ndarray, (m, 3, 2) float64
        ``(s, t)`` per face corner in tile units.
    singular : numpy.ndarray, (m,) bool
    scale : numpy.ndarray, (n,) float64
        Tile size per vertex in surface units.
    cones : tuple of (int, float)
        ``(vertex, index)`` of the cross field's singular vertices.
    functions : numpy.ndarray, (n, 4) float64
        The periodic functions (see :class:`~geotex.param.pgp.PeriodicParameterization`).
    axes : numpy.ndarray, (m, 3) float64
        The combed cross-field arm of every face.
    metadata : dict
    """

    coords: np.ndarray
    singular: np.ndarray
    scale: np.ndarray
    cones: tuple
    functions: np.ndarray
    axes: np.ndarray
    metadata: dict = field(default_factory=dict)

    @property
    def eigenvalues(self) -> tuple:
        """Not stored in files (a local update reports none)."""
        return ()


def save_parameterization(path, p, *, metadata: dict | None = None) -> Path:
    """Write a :class:`~geotex.param.pgp.PeriodicParameterization` (atomically).

    Parameters
    ----------
    path : str or os.PathLike
        ``.npz`` file.
    p : PeriodicParameterization
    metadata : dict, optional
        JSON-serialisable; ``format`` is set to :data:`PGP_FORMAT`.

    Returns
    -------
    pathlib.Path

    Raises
    ------
    InputError
        If the path does not end in ``.npz``.
    """
    meta = dict(metadata or {}, format=PGP_FORMAT)
    return write_record(path, {
        "coords": p.coords, "singular": p.singular, "scale": p.scale,
        "cone_vertices": np.array([v for v, _ in p.cones], dtype=np.int64),
        "cone_indices": np.array([k for _, k in p.cones], dtype=np.float64),
        "functions": p.functions, "axes": p.axes,
        "metadata": np.array(json.dumps(meta))}, compressed=True, kind="PGP")


def load_parameterization(path) -> PgpFile:
    """Read a file written by :func:`save_parameterization` (or ``geotex pgp``).

    Returns
    -------
    PgpFile

    Raises
    ------
    MissingFileError
        If the file does not exist.
    MeshFileError
        If it is not a geotex PGP file, is damaged, or its arrays disagree.
    """
    d, meta = read_record(path, kind="PGP", format=PGP_FORMAT, record="geotex PGP file",
                          arrays=("coords", "singular", "scale", "cone_vertices",
                                  "cone_indices", "functions", "axes"),
                          hint="make one with 'geotex pgp'")
    coords, singular, scale = d["coords"], d["singular"], d["scale"]
    functions, axes = d["functions"], d["axes"]
    m = coords.shape[0] if coords.ndim == 3 else -1
    n = scale.shape[0] if scale.ndim == 1 else -1
    if (coords.shape != (m, 3, 2) or singular.shape != (m,) or functions.shape != (n, 4)
            or axes.shape != (m, 3) or d["cone_vertices"].shape != d["cone_indices"].shape
            or not np.isfinite(coords).all()):
        raise MeshFileError(path, "inconsistent PGP file (array shapes do not match); "
                                  "make it again with 'geotex pgp'")
    cones = tuple((int(v), float(k)) for v, k in zip(d["cone_vertices"], d["cone_indices"]))
    return PgpFile(np.asarray(coords, np.float64), np.asarray(singular, bool),
                   np.asarray(scale, np.float64), cones, np.asarray(functions, np.float64),
                   np.asarray(axes, np.float64), meta)
