"""A solid as a print file stores it, cleaned so that it survives the storing.

A validity verdict is only worth something for the coordinates a file really
holds. Binary STL (and GLB) store float32: rounding a float64 solid can
collapse the short edges and needle triangles a boolean leaves, or fold them
onto their neighbours, and a reader that welds equal corners (geotex's own
STL reader, every slicer) then sees non-manifold edges. The text formats
(3MF, OBJ, PLY, OFF) store every float64 exactly (shortest ``repr``).

:func:`stored_form` gives the arrays a reader gets back from a file;
:func:`printable_stored_solid` rounds a solid, removes what the rounding
broke (manifold3d rebuilds it from the rounded coordinates, collapsing
zero-length edges and degenerate triangles, then, if needed, simplifies at a
few float32 steps) and judges the result exactly as stored.
"""

from __future__ import annotations

from dataclasses import dataclass

import manifold3d as m3d
import numpy as np

from geotex.check.report import CheckReport, check_mesh
from geotex.errors import InputError
from geotex.io import weld_exact
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.solid import arrays_of_manifold, manifold_of
from geotex.mesh.topology import numbered_by_first_use

__all__ = ["stored_precision", "stored_form", "printable_stored_solid", "StoredSolid"]

#: Formats whose coordinates are float32 (binary STL, glTF); the others store
#: float64 exactly.
FLOAT32_FORMATS = (".stl", ".glb")



def stored_precision(suffix: str) -> type:
    """Coordinate type a print format stores: ``numpy.float32`` or ``numpy.float64``.

    Parameters
    ----------
    suffix : str
        File extension with its dot (``".stl"``), any case.

    Returns
    -------
    type
    """
    return np.float32 if str(suffix).lower() in FLOAT32_FORMATS else np.float64


def stored_form(V, F, *, precision=np.float32) -> tuple[np.ndarray, np.ndarray]:
    """The mesh a reader gets back: rounded coordinates, equal corners welded.

    Coordinates are rounded to ``precision``; corners at exactly equal
    positions become one vertex, numbered in order of first appearance in
    ``F`` (as geotex's STL reader does); unreferenced vertices disappear.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    precision : type, optional
        ``numpy.float32`` or ``numpy.float64``.

    Returns
    -------
    V2 : numpy.ndarray, (p, 3) float64
        Values exactly representable in ``precision``.
    F2 : numpy.ndarray, (m, 3) int64
        ``F`` itself (not a copy) when nothing welds and its vertices are
        already numbered by first use.

    Raises
    ------
    InputError
        Malformed arrays, or coordinates outside the float32 range.
    """
    V, F = as_mesh_arrays(V, F)
    precision = np.dtype(precision)
    if precision not in (np.dtype(np.float32), np.dtype(np.float64)):
        raise InputError(f"precision must be float32 or float64, got {precision}")
    if precision == np.float32 and V.size and np.abs(V).max() > np.finfo(np.float32).max:
        raise InputError("coordinates exceed the float32 range of the file format; "
                         "scale the model down or write a .3mf")
    # welding the vertices (not the 3m corners) and numbering the welded ones
    # by first appearance in F gives the same arrays, bit for bit, at a third
    # of the cost: equal corners are corners of equal vertices
    unique, welded = weld_exact(V.astype(precision))
    if unique.shape[0] == V.shape[0] and numbered_by_first_use(F, V.shape[0]):
        # nothing welded (``welded`` is the identity) and the vertices already
        # in order of first use: the faces stay as they are (the relief's
        # solids, numbered by first use before they are judged)
        return unique.astype(np.float64), F
    W = welded[F]
    first = np.full(unique.shape[0], W.size, dtype=np.int64)
    np.minimum.at(first, W.ravel(), np.arange(W.size))
    used = np.flatnonzero(first < W.size)
    order = used[np.argsort(first[used], kind="stable")]
    rank = np.empty(unique.shape[0], dtype=np.int64)
    rank[order] = np.arange(order.size)
    return unique[order].astype(np.float64), rank[W]


@dataclass(frozen=True)
class StoredSolid:
    """A solid rounded to a file's precision and judged as stored.

    Attributes
    ----------
    vertices : numpy.ndarray, (n, 3) float64
        Exactly representable in the format's precision; distinct positions.
    faces : numpy.ndarray, (m, 3) int64
    report : CheckReport
        Validity of exactly these arrays (``report.digest`` matches them).
    rebuilt : bool
        Whether manifold3d rebuilt the rounded solid.
    collapsed_faces : int
        Faces the rebuild removed (zero-area after rounding).
    """

    vertices: np.ndarray
    faces: np.ndarray
    report: CheckReport
    rebuilt: bool = False
    collapsed_faces: int = 0


def printable_stored_solid(V, F, *, precision=np.float32, rebuild: bool = False,
                           manifold3d: bool = True, max_examples: int = 5,
                           progress=None, on_stored=None) -> StoredSolid:
    """Round a solid to a file's precision, repair what rounding broke, judge it.

    The solid is judged as stored (:func:`stored_form`); if that fails (or
    at once with ``rebuild``), manifold3d rebuilds it from the rounded
    coordinates, which collapses the zero-length edges and zero-area
    triangles the rounding made, and the rebuilt solid, rounded again, is
    judged as stored. Vertices only move onto other vertices' rounded
    positions. Needle triangles that rounding would fold are best removed
    before rounding (the union simplifies at a small tolerance,
    :data:`geotex.mesh.needles.SLIVER_TOLERANCE`).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        A closed solid (for example the result of a boolean union).
    precision : type, optional
        ``numpy.float32`` (binary STL, GLB) or ``numpy.float64`` (3MF and
        text formats).
    rebuild : bool, optional
        Rebuild before the first verdict (saves a check when the rounding is
        known to break slivers, as after a boolean).
    manifold3d : bool, optional
        Ask manifold3d for its verdict too (see
        :func:`~geotex.check.report.check_mesh`).
    max_examples : int, optional
        Offending elements kept in the report's ``examples``.
    progress : callable, optional
        Passed to :func:`~geotex.check.report.check_mesh`.
    on_stored : callable, optional
        Called with the arrays ``(V, F)`` about to be judged, before each
        check runs (a :class:`geotex.printing.StagedWrite` then writes them
        while they are judged); the returned solid holds the arrays of the
        last call.

    Returns
    -------
    StoredSolid
        The rebuilt solid when it was rebuilt, else the solid as stored.

    Raises
    ------
    InputError
        Malformed arrays or coordinates outside the float32 range.
    """
    def judged(Vx, Fx):
        if on_stored is not None:
            on_stored(Vx, Fx)
        return check_mesh(Vx, Fx, manifold3d=manifold3d, max_examples=max_examples,
                          progress=progress)

    Vs, Fs = stored_form(V, F, precision=precision)
    if not rebuild or Fs.shape[0] == 0:
        rep = judged(Vs, Fs)
        if rep.printable or Fs.shape[0] == 0:
            return StoredSolid(Vs, Fs, rep)
    solid = manifold_of(Vs, Fs)
    if solid.status() != m3d.Error.NoError:     # not a solid: nothing to rebuild
        return StoredSolid(Vs, Fs, judged(Vs, Fs))
    Vc, Fc = stored_form(*arrays_of_manifold(solid), precision=precision)
    return StoredSolid(Vc, Fc, judged(Vc, Fc), True, Fs.shape[0] - Fc.shape[0])
