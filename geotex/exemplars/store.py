"""Saving and loading exemplars: ``.npz`` keeps the recipe, mesh files keep the geometry."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from geotex.errors import InputError, MeshFileError, MissingFileError
from geotex.exemplars.record import Exemplar
from geotex.io import read_mesh, write_mesh
from geotex.io.records import read_record, write_record
from geotex.mesh.topology import edge_topology

__all__ = ["save_exemplar", "load_exemplar", "FORMAT_TAG"]

#: Format tag stored in the metadata of ``.npz`` exemplar files.
FORMAT_TAG = "geotex-exemplar-1"


def save_exemplar(path, ex: Exemplar) -> Path:
    """Write an exemplar atomically.

    Parameters
    ----------
    path : str or os.PathLike
        ``.npz``: vertices, faces and a JSON ``metadata`` string (size, height,
        depth, name, params, period): a lossless round trip.  Any extension
        :func:`geotex.io.write_mesh` supports (``.stl``, ``.obj``, ``.ply``,
        ``.off``, ``.3mf``, ``.glb``): the geometry only (the recipe is lost;
        float32 formats round the coordinates).
    ex : Exemplar

    Returns
    -------
    pathlib.Path

    Raises
    ------
    InputError
        If ``ex`` is not an :class:`Exemplar` or its params are not JSON serialisable.
    UnsupportedFormatError, MeshFileError
        On an unsupported extension or a write failure (nothing is left behind).
    """
    if not isinstance(ex, Exemplar):
        raise InputError(f"ex must be a geotex.exemplars.Exemplar, got {type(ex).__name__}")
    path = Path(path)
    if path.suffix.lower() != ".npz":
        return write_mesh(path, ex.mesh())
    try:
        meta = json.dumps({"format": FORMAT_TAG, "size": list(ex.size), "height": ex.height,
                           "depth": ex.depth, "name": ex.name, "params": ex.params,
                           "period": None if ex.period is None else list(ex.period)},
                          sort_keys=True)
    except (TypeError, ValueError) as exc:
        raise InputError(f"ex.params is not JSON serialisable: {exc}") from None
    return write_record(path, dict(vertices=ex.vertices, faces=ex.faces,
                                   metadata=np.array(meta)), compressed=False)


def _load_npz(path: Path) -> Exemplar:
    z, m = read_record(path, kind="exemplar", format=FORMAT_TAG, arrays=("vertices", "faces"),
                       hint="save one with 'geotex exemplar' or load a mesh file")
    try:
        return Exemplar(z["vertices"], z["faces"], size=tuple(m["size"]), height=m["height"],
                        depth=m["depth"], name=m["name"], params=m["params"],
                        period=m.get("period"))
    except (ValueError, KeyError, TypeError, InputError) as exc:
        raise MeshFileError(path, f"bad exemplar metadata: {exc}") from None


def load_exemplar(path) -> Exemplar:
    """Read an exemplar from ``.npz`` (lossless) or from any mesh file.

    A plain mesh file becomes an exemplar whose elements are its connected
    components: it is moved so that the minimum corner of its XY bounding box
    is the origin, ``size`` is the XY extent, ``height`` the largest and
    ``-depth`` the smallest ``z``; ``name`` is the file stem and ``params``
    is empty.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    Exemplar

    Raises
    ------
    MissingFileError
        If the file does not exist.
    MeshFileError
        If the file cannot be read, has no faces, or (mesh files) some element
        is not closed: every edge must belong to exactly two faces.
    """
    path = Path(path)
    if not path.is_file():
        raise MissingFileError(f"{path}: no such file")
    if path.suffix.lower() == ".npz":
        return _load_npz(path)
    mesh = read_mesh(path)
    V, F = mesh.vertices, mesh.faces
    if F.shape[0] == 0:
        raise MeshFileError(path, "the mesh has no faces; an exemplar needs closed elements")
    topo = edge_topology(F, V.shape[0])
    if topo.boundary.size or topo.non_manifold.size:
        raise MeshFileError(
            path, f"not an exemplar: its elements must be closed, but {topo.boundary.size} "
                  f"edges are open and {topo.non_manifold.size} have more than two faces; "
                  "repair it first (geotex repair)")
    V = V - np.array([V[:, 0].min(), V[:, 1].min(), 0.0])
    return Exemplar(V, F, size=(float(V[:, 0].max()), float(V[:, 1].max())),
                    height=float(V[:, 2].max()), depth=float(-V[:, 2].min()),
                    name=path.stem, params={})
