"""Texture inputs: plain ``(V, F, size)`` arrays or an exemplar object, split into elements.

An *element* is one closed connected component of a geometric texture.  The
quilting code keeps the texture as a list of :class:`Element` records (the
arrays of one component, its fixed-vertex mask and its bounding box) and only
concatenates them at the end.
"""

from __future__ import annotations

from dataclasses import dataclass

import manifold3d
import numpy as np

from geotex.errors import InputError
from geotex.mesh.arrays import as_faces, as_mesh_arrays
from geotex.check.intersections import self_intersecting_pairs
from geotex.mesh.geometry import degenerate_faces, face_areas, face_normals, signed_volume
from geotex.mesh.polygons import without_flat_triangles
from geotex.mesh.topology import (compacted, edge_topology, face_components,
                                  non_manifold_vertices)
from geotex.quilting.icp import ClosestPoints
from geotex.quilting.seam import boundary_loops

__all__ = ["Element", "texture_arrays", "split_elements", "concatenate_elements",
           "closed_element_ok", "capped", "caps_like"]


@dataclass
class Element:
    """One closed component of a texture.

    Attributes
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    fixed : numpy.ndarray, (n,) bool
        Vertices that must never move.
    prefilled : bool
        True for elements given by the caller (they may leave the domain).
    cap : numpy.ndarray, (m,) bool, optional
        Faces that only close a prefilled element cut open by a domain side
        (see :func:`capped`); they are left out of the output.

    Notes
    -----
    Elements are replaced, never edited: the bounding box is computed on
    construction and the closest-point tree (:attr:`closest`) on first use,
    so the many contact tests of the quilting loop share them.
    """

    V: np.ndarray
    F: np.ndarray
    fixed: np.ndarray
    prefilled: bool = False
    cap: np.ndarray = None

    def __post_init__(self):
        #: bounding box corners, (3,) each
        self.lo = self.V.min(axis=0)
        self.hi = self.V.max(axis=0)
        if self.cap is None:
            self.cap = np.zeros(self.F.shape[0], dtype=bool)
        self._closest = None

    @property
    def closest(self):
        """:class:`~geotex.quilting.icp.ClosestPoints` of the element (its AABB tree)."""
        if self._closest is None:
            self._closest = ClosestPoints(self.V, self.F)
        return self._closest


def texture_arrays(texture, F=None, size=None) -> tuple[np.ndarray, np.ndarray, tuple, object]:
    """Normalise a texture argument.

    Parameters
    ----------
    texture : array_like (n, 3) or exemplar-like object
        Vertex array (with ``F`` and ``size``), or an object with ``vertices``,
        ``faces``, ``size`` and optionally ``elements()`` (per-face element
        ids), such as :class:`geotex.exemplars.Exemplar`.
    F : array_like, (m, 3) int64, optional
    size : tuple (lx, ly), optional
        Extent of the texture in the plane, ``[0, lx] x [0, ly]``; defaults to
        the object's ``size``.

    Returns
    -------
    V, F, size, element_ids
        ``element_ids`` is the per-face id array from the object, or None.

    Raises
    ------
    InputError
        On malformed arrays, a missing or non-positive size.
    """
    ids = None
    if hasattr(texture, "vertices") and hasattr(texture, "faces"):
        V, Fa = as_mesh_arrays(texture.vertices, texture.faces, allow_empty=False)
        if size is None:
            size = getattr(texture, "size", None)
        if hasattr(texture, "elements"):
            ids = np.asarray(texture.elements(), dtype=np.int64)
    else:
        if F is None:
            raise InputError("texture faces F are missing: pass (V, F, size=...) "
                             "or an exemplar object")
        V, Fa = as_mesh_arrays(texture, F, allow_empty=False)
    if size is None:
        raise InputError("size=(lx, ly) of the texture is required")
    try:
        lx, ly = (float(s) for s in size)
    except (TypeError, ValueError):
        raise InputError(f"size must be two numbers (lx, ly), got {size!r}") from None
    if not (lx > 0 and ly > 0 and np.isfinite([lx, ly]).all()):
        raise InputError(f"size must be positive, got {size!r}")
    return V, Fa, (lx, ly), ids


def split_elements(V, F, *, fixed=None, element_ids=None, prefilled=False) -> list[Element]:
    """Split a texture into its elements (connected components unless ids are given).

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    fixed : array_like of int or (n,) bool, optional
        Fixed vertices of the whole texture.
    element_ids : numpy.ndarray, (m,) int64, optional
    prefilled : bool, optional

    Returns
    -------
    list of Element
        In order of the smallest face index of each element.
    """
    n = V.shape[0]
    F = as_faces(F, n)
    fix = np.zeros(n, dtype=bool)
    if fixed is not None:
        arr = np.asarray(fixed)
        if arr.dtype == bool:
            if arr.shape != (n,):
                raise InputError(f"fixed as a mask must have shape ({n},), got {arr.shape}")
            fix = arr.copy()
        else:
            arr = np.asarray(arr, dtype=np.int64).ravel()
            if arr.size and (arr.min() < 0 or arr.max() >= n):
                raise InputError(f"fixed holds vertex indices outside [0, {n})")
            fix[arr] = True
    if element_ids is None:
        _, labels = face_components(F, n)
    else:
        labels = np.asarray(element_ids, dtype=np.int64).ravel()
        if labels.shape[0] != F.shape[0]:
            raise InputError(f"element ids need one value per face ({F.shape[0]})")
    order = np.argsort(labels, kind="stable")
    bounds = np.flatnonzero(np.diff(labels[order])) + 1
    groups = np.split(order, bounds)
    groups.sort(key=lambda g: int(g[0]))
    out = []
    for faces in groups:
        Ve, Fe, used = compacted(V, F[faces], return_index=True)
        out.append(Element(Ve, Fe, fix[used].copy(), prefilled))
    return out


def concatenate_elements(elements: list[Element]):
    """Concatenate elements into ``(V, F, element_ids (m,), fixed (n,))``, caps left out."""
    if not elements:
        return (np.zeros((0, 3)), np.zeros((0, 3), np.int64), np.zeros(0, np.int64),
                np.zeros(0, bool))
    offsets = np.cumsum([0] + [e.V.shape[0] for e in elements])
    V = np.concatenate([e.V for e in elements])
    F = np.concatenate([e.F[~e.cap] + o for e, o in zip(elements, offsets)])
    ids = np.concatenate([np.full(int((~e.cap).sum()), i, np.int64)
                          for i, e in enumerate(elements)])
    fixed = np.concatenate([e.fixed for e in elements])
    return np.ascontiguousarray(V), np.ascontiguousarray(F), ids, fixed


def closed_element_ok(V: np.ndarray, F: np.ndarray, *, intersections: bool = True) -> str:
    """Return ``""`` when ``(V, F)`` is one valid closed solid, else the first problem.

    Checks: closed, edge- and vertex-manifold, consistently oriented, no
    degenerate faces, positive volume, one connected component, and (unless
    ``intersections`` is false) no self-intersection.
    """
    if F.shape[0] < 4:
        return "too few faces"
    topo = edge_topology(F, V.shape[0])
    if topo.boundary.size:
        return f"{topo.boundary.size} boundary edges"
    if topo.non_manifold.size:
        return f"{topo.non_manifold.size} non-manifold edges"
    if topo.inconsistent.size:
        return "inconsistent orientation"
    if non_manifold_vertices(F, V.shape[0], topo).size:
        return "non-manifold vertices"
    if degenerate_faces(V, F).size:
        return "degenerate faces"
    if not signed_volume(V, F) > 0:
        return "non-positive volume"
    if face_components(F, V.shape[0])[0] != 1:
        return "several components"
    if intersections and self_intersecting_pairs(V, F, max_pairs=1).size:
        return "self-intersection"
    return ""


def capped(V: np.ndarray, F: np.ndarray, domain, *, rel_tol: float = 1e-9):
    """Close the openings of an element cut open along the domain's edges.

    Wang tile frames hold halves of elements cut by the tile sides: open
    meshes whose boundary loops lie on the lines ``x = x0``, ``x = x1``,
    ``y = y0`` or ``y = y1`` (vertical planes).  Each plane's loops are
    triangulated together (holes included) with manifold3d in that plane and
    oriented to match the element, so the capped element is closed and the
    quilting code can treat it like any other (inside tests, merging).

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    domain : tuple (x0, y0, x1, y1)
    rel_tol : float, optional
        Distance to the plane allowed, relative to the domain size.

    Returns
    -------
    F2 : numpy.ndarray, (m + c, 3) int64
        ``F`` followed by the ``c`` cap triangles (no new vertices).
    cap : numpy.ndarray, (m + c,) bool
        True for the cap triangles.
    on_cut : numpy.ndarray, (n,) bool
        Vertices of the cut loops.

    Raises
    ------
    InputError
        If a boundary loop does not lie on one domain edge, or cannot be
        capped.
    """
    n = V.shape[0]
    on_cut = np.zeros(n, dtype=bool)
    loops = boundary_loops(F, n)
    if loops is None:
        raise InputError("a prefilled element has a non-manifold boundary")
    if not loops:
        return F, np.zeros(F.shape[0], bool), on_cut
    x0, y0, x1, y1 = (float(d) for d in domain)
    tol = rel_tol * max(x1 - x0, y1 - y0)
    planes = {}
    sides = (("x0", 0, x0), ("x1", 0, x1), ("y0", 1, y0), ("y1", 1, y1))
    for loop in loops:
        P = V[loop]
        for key, axis, value in sides:
            if np.abs(P[:, axis] - value).max() <= tol:
                planes.setdefault((key, axis), []).append(loop)
                break
        else:
            parts = _corner_parts(loop, P, sides, tol)
            if parts is None:
                raise InputError("a prefilled element is open away from the domain edges "
                                 f"(boundary loop at {P.mean(axis=0).round(4).tolist()}): "
                                 "prefilled elements must be closed or cut by the domain "
                                 "sides")
            for plane, part in parts:
                planes.setdefault(plane, []).append(part)
    caps = []
    for (_, axis), group in planes.items():
        other = 1 - axis
        polys = [np.ascontiguousarray(V[l][:, [other, 2]]) for l in group]
        ids = np.concatenate(group)
        try:
            tri = np.asarray(manifold3d.triangulate(polys, 1e-12), dtype=np.int64).reshape(-1, 3)
        except Exception:  # noqa: BLE001 - the triangulator rejects bad outlines
            tri = np.zeros((0, 3), np.int64)
        if tri.shape[0] == 0:
            raise InputError("a prefilled element's cut opening could not be capped")
        # straight runs of the outline (e.g. along the flat bottom) give flat ears
        tri = without_flat_triangles(np.concatenate(polys), tri)
        group_caps = ids[tri]
        # each plane's caps are oriented on their own (an element cut at a
        # corner has caps in two planes, sharing the corner edge)
        if edge_topology(np.r_[F, group_caps], n).inconsistent.size:
            group_caps = group_caps[:, ::-1]
        caps.append(group_caps)
        on_cut[ids] = True
    cap_faces = np.concatenate(caps)
    F2 = np.ascontiguousarray(np.r_[F, cap_faces])
    cap = np.r_[np.zeros(F.shape[0], bool), np.ones(cap_faces.shape[0], bool)]
    return F2, cap, on_cut


def _corner_parts(loop, P, sides, tol):
    """Split a boundary loop that runs along two adjacent domain sides at their corner.

    An element cut by both lines through a domain corner (a Wang tile's
    corner patch) has one opening lying in two planes, ``x = x0 or x1`` and
    ``y = y0 or y1``, meeting at the vertical line through the corner.  When
    the loop passes that line at exactly two vertices, it is split there
    into its run in each plane; each run, closed by the chord between the
    two corner vertices, is capped in its plane, and the two caps share the
    chord.  Returns ``[((key, axis), run), ...]`` or ``None``.
    """
    for kx, ax, vx in sides[:2]:
        on_x = np.abs(P[:, ax] - vx) <= tol
        for ky, ay, vy in sides[2:]:
            on_y = np.abs(P[:, ay] - vy) <= tol
            both = np.flatnonzero(on_x & on_y)
            if not (on_x | on_y).all() or both.size != 2:
                continue
            i, j = int(both[0]), int(both[1])
            first = loop[i:j + 1]
            second = np.r_[loop[j:], loop[:i + 1]]
            run_x = first if on_x[i:j + 1].all() else second
            run_y = second if run_x is first else first
            if not (on_x[np.isin(loop, run_x)].all() and on_y[np.isin(loop, run_y)].all()):
                continue
            if run_x.size < 3 or run_y.size < 3:
                continue
            return [((kx, ax), run_x), ((ky, ay), run_y)]
    return None


def caps_like(V, F, VA, caps):
    """Find the caps again after a boolean union changed an element's faces.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        The new element.
    VA : numpy.ndarray, (k, 3) float64
    caps : numpy.ndarray, (c, 3) int64
        The cap faces of the old element (indices into ``VA``).

    Returns
    -------
    numpy.ndarray (m,) bool or None
        Faces of ``(V, F)`` lying in the planes of the old caps and facing
        the same way; None when they do not cover the same area (the union
        changed the cut opening).
    """
    scale = float(np.abs(VA).max()) or 1.0
    tol = 1e-9 * scale
    Nc = face_normals(VA, caps)
    axis = np.argmax(np.abs(Nc), axis=1)
    value = VA[caps[:, 0], axis]
    planes = np.unique(np.c_[axis, value, np.sign(Nc[np.arange(len(caps)), axis])], axis=0)
    N = face_normals(V, F)
    mask = np.zeros(F.shape[0], bool)
    for ax, val, sign in planes:
        ax = int(ax)
        on = (np.abs(V[F][:, :, ax] - val) <= tol).all(axis=1) & (np.sign(N[:, ax]) == sign)
        mask |= on
    if abs(face_areas(V, F)[mask].sum() - face_areas(VA, caps).sum()) > 1e-6 * face_areas(
            VA, caps).sum():
        return None
    return mask
