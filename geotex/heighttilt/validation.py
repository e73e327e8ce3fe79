"""Validation of a height-and-tilt base (re-exported by :mod:`geotex.heighttilt.base`).

It sits below :mod:`~geotex.heighttilt.base` and :mod:`~geotex.heighttilt.smoothing`,
which both validate their input with it, so neither imports the other lazily.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.heighttilt._kernels import BaseGeometry
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.topology import EdgeTopology

__all__ = ["check_base_mesh", "base_geometry"]


def check_base_mesh(V, F, *, name: str = "V") -> tuple[np.ndarray, np.ndarray]:
    """Validate a mesh used as (or to build) a height-and-tilt base.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    name : str, optional
        Name of the vertex argument, used in messages.

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64

    Raises
    ------
    InputError
        Empty vertices or faces; zero-area faces (no normal, no cotangent
        weights); edges shared by more than two faces (no tangent plane);
        vertices referenced by no face (no normal).  Open (boundary) meshes
        are accepted.
    """
    g = base_geometry(V, F, name=name)
    return g.V, g.F


def base_geometry(V, F, *, name: str = "V", topology: EdgeTopology | None = None
                  ) -> BaseGeometry:
    """Validate a base (see :func:`check_base_mesh`) and return its shared geometry.

    The face geometry, edge topology, valences and base normals are computed
    once here and reused by extraction, reconstruction and the tilt codec.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    name : str, optional
        Name of the vertex argument, used in messages.
    topology : EdgeTopology, optional
        ``edge_topology(F, len(V))``, to reuse.

    Returns
    -------
    geotex.heighttilt._kernels.BaseGeometry

    Raises
    ------
    InputError
        As :func:`check_base_mesh`; also when the incident face normals of a
        vertex cancel (no base normal there).
    """
    V, F = as_mesh_arrays(V, F)
    if V.shape[0] == 0:
        raise InputError(f"{name} is empty: a height-and-tilt base needs vertices")
    if F.shape[0] == 0:
        raise InputError("F is empty: a height-and-tilt base needs faces")
    if topology is not None and (not isinstance(topology, EdgeTopology)
                                 or topology.half_to_edge.shape != (3 * F.shape[0],)):
        raise InputError("topology does not belong to F: pass edge_topology(F, len(V)) "
                         "computed for this mesh, or leave it out")
    g = BaseGeometry(V, F, topology)
    if g.flat.any():
        bad = np.flatnonzero(g.flat)
        raise InputError(f"F has {bad.size} zero-area faces in {name} (first: face {int(bad[0])}); "
                         "remove them (geotex.repair) before extracting a texture")
    nm = g.topo.non_manifold
    if nm.size:
        raise InputError(f"F has {nm.size} non-manifold edges (shared by more "
                         "than two faces); repair the mesh first")
    unused = g.valence == 0
    if unused.any():
        raise InputError(f"{name} has {int(unused.sum())} vertices used by no face "
                         f"(first: {int(np.flatnonzero(unused)[0])}); remove them first")
    acc = g.unit_sum_normals()
    ln = np.linalg.norm(acc, axis=1, keepdims=True)
    if np.any(ln[:, 0] <= 1e-12):
        v = int(np.flatnonzero(ln[:, 0] <= 1e-12)[0])
        raise InputError(f"{name} has a vertex whose incident face normals cancel (vertex {v}); "
                         "the base normal is undefined there")
    g.set_normals(acc / ln)
    return g
