"""Assertions for users' own pytest suites.

Each assertion accepts a :class:`~geotex.mesh.Mesh`, a ``(V, F)`` pair, or a
path to a mesh file, and raises ``AssertionError`` whose message says what is
wrong and where: counts and the first offending faces, edges or vertices.

Examples
--------
>>> import numpy as np
>>> from geotex.testing import assert_printable
>>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
>>> F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
>>> assert_printable(V, F).printable          # passes, returning the report
True
"""

from __future__ import annotations

import os

import igl
import numpy as np

from geotex.check.intersections import self_intersecting_pairs
from geotex.check.report import CheckReport, check_mesh
from geotex.check.slicers import slicer_verdicts
from geotex.errors import InputError
from geotex.io import read_mesh, write_mesh
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.record import Mesh
from geotex.mesh.topology import edge_topology, non_manifold_vertices, position_welded_faces

__all__ = [
    "assert_printable", "assert_watertight", "assert_manifold",
    "assert_no_self_intersections", "assert_meshes_close", "hausdorff_distance",
    "assert_slicer_accepts",
]


def _arrays(mesh, F=None) -> tuple[np.ndarray, np.ndarray, str]:
    if F is not None:
        V, F = as_mesh_arrays(mesh, F)
        return V, F, "mesh"
    if isinstance(mesh, Mesh):
        return mesh.vertices, mesh.faces, mesh.name or "mesh"
    if isinstance(mesh, (str, os.PathLike)):
        m = read_mesh(mesh)
        return m.vertices, m.faces, str(mesh)
    if isinstance(mesh, tuple) and len(mesh) == 2:
        V, F = as_mesh_arrays(*mesh)
        return V, F, "mesh"
    raise InputError("mesh: expected a Mesh, a (V, F) pair, V and F, or a file path")


def assert_printable(mesh, F=None, *, msg: str = "") -> CheckReport:
    """Assert the mesh is a printable solid (see :func:`geotex.check.check_mesh`).

    Returns
    -------
    CheckReport
        The report, for further assertions.
    """
    V, F, label = _arrays(mesh, F)
    report = check_mesh(V, F)
    if not report.printable:
        lines = [f"{label} is not printable:"]
        lines += [f"  - {r}" for r in report.reasons]
        lines += [f"  first {k.replace('_', ' ')}: {v}" for k, v in report.examples.items()]
        raise AssertionError((msg + "\n" if msg else "") + "\n".join(lines))
    return report


def assert_watertight(mesh, F=None, *, msg: str = "") -> None:
    """Assert every edge has exactly two faces (no holes, no non-manifold edges)."""
    V, F, label = _arrays(mesh, F)
    if F.shape[0] == 0:
        raise AssertionError(f"{msg}{label} has no faces")
    topo = edge_topology(F, V.shape[0])
    problems = []
    if topo.boundary.size:
        problems.append(f"{topo.boundary.size} boundary edges, first "
                        f"{topo.edges[topo.boundary[:5]].tolist()}")
    if topo.non_manifold.size:
        problems.append(f"{topo.non_manifold.size} edges with more than two faces, first "
                        f"{topo.edges[topo.non_manifold[:5]].tolist()}")
    if problems:
        raise AssertionError(f"{msg}{label} is not watertight: " + "; ".join(problems))


def assert_manifold(mesh, F=None, *, msg: str = "") -> None:
    """Assert every edge has at most two faces and every vertex one fan."""
    V, F, label = _arrays(mesh, F)
    topo = edge_topology(F, V.shape[0])
    nmv = non_manifold_vertices(F, V.shape[0], topo)
    problems = []
    if topo.non_manifold.size:
        problems.append(f"{topo.non_manifold.size} non-manifold edges, first "
                        f"{topo.edges[topo.non_manifold[:5]].tolist()}")
    if nmv.size:
        problems.append(f"{nmv.size} non-manifold vertices, first {nmv[:5].tolist()}")
    if problems:
        raise AssertionError(f"{msg}{label} is not manifold: " + "; ".join(problems))


def assert_no_self_intersections(mesh, F=None, *, msg: str = "") -> None:
    """Assert no two faces of the mesh intersect (see ``self_intersecting_pairs``)."""
    V, F, label = _arrays(mesh, F)
    pairs = self_intersecting_pairs(V, position_welded_faces(V, F))
    if pairs.shape[0]:
        first = pairs[0]
        where = V[F[first[0]]].mean(axis=0)
        raise AssertionError(
            f"{msg}{label} has {pairs.shape[0]} self-intersecting face pairs, first "
            f"{pairs[:5].tolist()} (near {np.array2string(where, precision=4)})")


def assert_slicer_accepts(path, *, expected_parts: int | None = 1, msg: str = "") -> dict:
    """Assert PrusaSlicer and admesh accept a written mesh file as it is.

    Runs ``prusa-slicer --info`` and ``admesh`` on the file (see
    :mod:`geotex.check.slicers` for the strict criteria: nothing for the
    programs to repair, one part by default).  A 3MF file is judged by
    PrusaSlicer only.  A :class:`~geotex.mesh.Mesh` or ``(V, F)`` pair is
    written to a temporary binary STL first (float32, as a user would).

    Parameters
    ----------
    path : str, os.PathLike, Mesh or (V, F) pair
    expected_parts : int or None, optional
        Number of separate bodies expected; None accepts any.

    Returns
    -------
    dict
        The verdicts of :func:`geotex.check.slicers.slicer_verdicts`.

    Raises
    ------
    AssertionError
        If either program rejects the file or cannot load it.
    geotex.errors.ToolNotFoundError
        If ``prusa-slicer`` or ``admesh`` is not installed.
    """
    if isinstance(path, (str, os.PathLike)):
        verdicts, label = slicer_verdicts(path, expected_parts=expected_parts), str(path)
    else:
        import tempfile

        V, F, label = _arrays(path)
        with tempfile.TemporaryDirectory(prefix="geotex-test-") as tmp:
            stl = os.path.join(tmp, "mesh.stl")
            write_mesh(stl, Mesh(V, F))
            verdicts = slicer_verdicts(stl, expected_parts=expected_parts)
    failed = [(tool, v) for tool, v in verdicts.items() if v["ok"] is False]
    if failed:
        lines = [f"{label} is rejected by {', '.join(t for t, _ in failed)}:"]
        lines += [f"  - {tool}: {r}" for tool, v in failed for r in v["reasons"]]
        raise AssertionError((msg + "\n" if msg else "") + "\n".join(lines))
    return verdicts


def _samples(V: np.ndarray, F: np.ndarray) -> np.ndarray:
    """Vertices, edge midpoints and face centroids of a mesh."""
    tri = V[F]
    mids = 0.5 * (tri + np.roll(tri, -1, axis=1)).reshape(-1, 3)
    return np.vstack([V, mids, tri.mean(axis=1)])


def hausdorff_distance(VA, FA, VB, FB) -> tuple[float, np.ndarray]:
    """Return the symmetric Hausdorff distance and the point where it is reached.

    Distances are exact point-to-triangle distances from samples of each mesh
    (vertices, edge midpoints, face centroids) to the other mesh's surface.

    Returns
    -------
    distance : float
    where : numpy.ndarray, (3,) float64
        The sample point farthest from the other mesh.
    """
    VA, FA = as_mesh_arrays(VA, FA, allow_empty=False)
    VB, FB = as_mesh_arrays(VB, FB, allow_empty=False)
    best, where = -1.0, None
    for P, (V, F) in ((_samples(VA, FA), (VB, FB)), (_samples(VB, FB), (VA, FA))):
        d2, _, _ = igl.point_mesh_squared_distance(P, V, F)
        i = int(np.argmax(d2))
        if d2[i] > best:
            best, where = float(d2[i]), P[i]
    return float(np.sqrt(best)), where


def assert_meshes_close(actual, expected, *, atol: float = None, rtol: float = 1e-6,
                        msg: str = "") -> float:
    """Assert two meshes are within a Hausdorff distance of each other.

    Parameters
    ----------
    actual, expected : Mesh, (V, F) pair, or path
    atol : float, optional
        Absolute tolerance; default ``rtol`` times the bounding-box diagonal of
        ``expected``.
    rtol : float, optional
        Relative tolerance used when ``atol`` is not given.

    Returns
    -------
    float
        The measured Hausdorff distance.
    """
    VA, FA, la = _arrays(actual)
    VB, FB, lb = _arrays(expected)
    for V, F, lab in ((VA, FA, la), (VB, FB, lb)):
        if F.shape[0] == 0:
            raise AssertionError(f"{msg}{lab} has no faces")
    if atol is None:
        atol = rtol * float(np.linalg.norm(VB.max(axis=0) - VB.min(axis=0)))
    d, where = hausdorff_distance(VA, FA, VB, FB)
    if d > atol:
        raise AssertionError(
            f"{msg}{la} and {lb} differ: Hausdorff distance {d:.6g} > tolerance {atol:.6g}, "
            f"reached at {np.array2string(where, precision=6)}")
    return d
