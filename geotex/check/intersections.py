"""Self-intersection detection for triangle meshes.

:func:`self_intersecting_pairs` reports every pair of faces whose triangles
intersect, in vectorized numpy: a broad phase on a hierarchical uniform grid,
then a tolerance-aware narrow phase, both on chunks of a bounded size.

Pipeline
--------
0. Faces with the same vertex set (duplicates, in any order or orientation)
   form one class; the pipeline runs on the first face of each class and
   the pairs are expanded to all members at the end, directly in sorted
   order (work linear in the output).  Many faces on few vertices therefore
   cost what their distinct triangles cost plus the size of the answer.
1. Coordinates are normalised in a copy: scaled by a power of two (exact) so
   that the bounding box of the referenced vertices has its largest extent in
   ``[1, 2)``, and centred on the origin.  Results therefore do not depend on
   the unit or the position, and meshes with coordinates near the float
   limits (``±3.4e38`` and beyond) cannot overflow.
2. Per face (in blocks): unit normal and plane offset, the three in-plane
   edge planes, the tolerance, and a float32 bounding box inflated by twice
   the tolerance.  Degenerate faces (repeated index, or
   ``|e0 x e1| <= 1e-12 * longest_edge**2``, the criterion of
   :func:`geotex.mesh.geometry.degenerate_faces`) take no part.
3. Separated fans: a vertex whose faces form a closed, consistently oriented
   disc that is a height field over its mean normal, winding once around it,
   with a margin far above the tolerance (:func:`_separated_fans`), cannot
   hold an intersecting pair of its faces; pairs sharing such a vertex are
   dropped before the narrow phase.  On a clean manifold mesh that is almost
   every pair of neighbours, so the narrow phase sees only faces that share
   no vertex (and the fans that fail the bound).
4. Broad phase, a hierarchical uniform grid: the finest cell is 1.5 times
   the median box size; level ``L`` has cells ``2**L`` times larger and
   holds the faces at most twice its cell size (so an even mesh lives on
   level 0 alone).
   Per level, its faces and the smaller faces sharing its cells are sorted
   by one packed int64 key (cell, level flag, face, corner flags), and in
   every cell each face of the level is paired with the entries after it.  A
   pair met in several cells is kept only in the cell holding the lower
   corner of the intersection of the two boxes (no pair is generated twice,
   no ``unique`` over pairs); the boxes (stored in entry order, so a cell's
   pairs read nearby memory) must overlap.  Pairs are enumerated in chunks
   of 200,000.
5. Narrow phase, on batches of 32,768 candidates: shared vertex indices
   decide the case, plane side tests reject most pairs, and the survivors
   get the case analysis described in :func:`self_intersecting_pairs`.

Chunks of candidate pairs (generation, filtering and narrow phase) run on a
small thread pool (numpy releases the GIL); results are gathered in a fixed
order, so the output does not depend on the scheduling.

From ``JIT_MIN_SIZE`` corner entries, steps 2-5 run as compiled loops
(:mod:`geotex.jit`, no GIL): the per-face data in blocks on the pool, the fan
terms and the vertex normal sums with the vertices split between the
threads, each level's grid (:func:`_level_grid`: entries, radix sort, pair
counts, no stored cell ranges; its loops over faces and entries in pieces
on the pool, each piece filling its own range) and the pair tasks over its
entries; the same pairs as the numpy path.

:func:`self_intersecting_pairs_touching` (pairs with a face of a subset) and
:func:`self_intersecting_pairs_between` (pairs between sides of parts, or
within chosen parts) return rows of the same answer without computing the
rest of it.
"""

from __future__ import annotations

import collections
import numbers
import os
from concurrent.futures import ThreadPoolExecutor
from functools import partial

import numpy as np

from geotex.errors import InputError
from geotex.jit import JIT_MIN_SIZE, compiled, helper
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.topology import edge_topology, has_twin_faces, unpaired_edge_vertices

__all__ = ["self_intersecting_pairs", "self_intersecting_pairs_touching",
           "self_intersecting_pairs_between", "offset_surface_pairs", "REL_TOL", "ABS_TOL"]

#: Tolerance of the geometric predicates relative to the local triangle size
#: (the longest edge of the two triangles of a pair).
REL_TOL = 1e-10
#: Absolute floor of the tolerance, in normalised coordinates (the bounding
#: box's largest extent is between 1 and 2), covering float64 rounding.
ABS_TOL = 1e-14

# Same criterion and default as geotex.mesh.geometry.degenerate_faces.
_DEGENERATE_REL_TOL = 1e-12
# Widening of the float32 boxes: more than two float32 ulps at magnitude 1.
_BOX32_PAD = 2.0 ** -21
# Finest grid cell: this ratio times the given quantile of the box sizes.
_BASE_QUANTILE = 0.5
_CELL_RATIO = 1.5
_LEVEL_RATIO = 2.0
# Candidate pairs enumerated per task, and faces per preparation block: both
# keep every temporary array to a few tens of MB.
_PAIR_CHUNK = 200_000
_FACE_BLOCK = 65_536
_NARROW_CHUNK = 32_768
_MAX_WORKERS = 4
# Safety factor of the fan separation bound (see _separated_fans).
_FAN_SAFETY = 8.0
# Largest part swept whole by parts= (a sweep is quadratic in the worst case);
# larger parts are swept in runs of _PART_RUN faces, consecutive in Morton
# order of their boxes' centres.
_PART_MAX_FACES = 4096
_PART_RUN = 256
# Meshes up to this many faces are searched by self_intersecting_pairs_between
# in the calling thread.
_SERIAL_FACES = 4096
# Bits of the packed sort key (cell, level flag, face, corner flags).
_KEY_BITS = 62
# Largest grid whose occupied cells the compiled grid marks in a bit array (32 MB);
# larger grids look cells up by binary search.
_OCC_CELLS = 1 << 28
# Smallest piece of the compiled grid's loops run on a thread of the pool.
_GRID_PIECE = 65_536


def self_intersecting_pairs(V, F, *, max_pairs=None, topology=None, unpaired_vertices=None,
                            distinct_faces: bool = False, parts=None, box=None) -> np.ndarray:
    """Return every pair of faces of a triangle mesh whose triangles intersect.

    Parameters
    ----------
    V : array_like, (n, 3) float64
        Vertex positions (finite).
    F : array_like, (m, 3) int64
        Triangles as vertex indices.
    max_pairs : int, optional
        Stop as soon as at least this many intersecting pairs are known.  The
        result then holds at most ``max_pairs`` pairs, still sorted, and is a
        subset of the full answer (not necessarily its first rows); the same
        inputs always give the same subset.  ``None`` (default) finds all.
    topology : geotex.mesh.topology.EdgeTopology, optional
        ``edge_topology(F, len(V))`` when the caller has it already (large
        meshes use it; it is computed otherwise).
    unpaired_vertices : array_like, (n,) bool, optional
        The vertices on an edge that is not used exactly once in each
        direction (a boundary, non-manifold or inconsistently oriented edge),
        when the caller knows them: all the search needs of the edge
        topology besides the grouping of duplicate faces (with
        ``distinct_faces`` no topology is then built or held, which is what
        the memory peak of :func:`geotex.check.report.check_mesh` needs).
    distinct_faces : bool, optional
        The caller knows that no two faces have the same vertex set (for
        example from :func:`geotex.mesh.topology.duplicate_face_groups`):
        the grouping of duplicate faces is skipped.  Wrong when there are
        duplicates: their pairs are then not expanded.
    parts : array_like, (m,) int, optional
        A part number for every face (for example its connected component).
        When the mesh is many small parts (mapped texture elements), candidate
        pairs are then enumerated by sweeping each part and each pair of parts
        whose boxes overlap instead of on the global grid: the same pairs are
        examined with the same predicates, so the answer is the same, at less
        cost.  Used only on the compiled path (from ``JIT_MIN_SIZE`` entries of
        ``F``), otherwise ignored; a part of more than 4096 faces is swept
        as runs of 256 faces in Morton order (the same pairs).  With
        ``max_pairs``, the sweep finds every pair
        first and keeps the lowest ``max_pairs``: a subset of the answer as
        without ``parts``, not necessarily the same subset.
    box : array_like, (2, 3) float64, optional
        Low and high corner of the box the coordinates are normalised by
        (module docstring, step 1) instead of the box of the referenced
        vertices; it must contain them.  Searches of meshes that share a box
        (a surface and its offsets at several heights) then see the same
        normalised coordinates for the same vertices, so the pairs of faces
        that did not move are the same pairs
        (:func:`self_intersecting_pairs_touching` with the same ``box``
        finds the others).

    Returns
    -------
    numpy.ndarray, (k, 2) int64
        Face index pairs ``(i, j)`` with ``i < j``, sorted lexicographically,
        without repetition.

    Raises
    ------
    InputError
        If ``V`` or ``F`` is malformed (shape, non-finite values, indices out
        of range), ``max_pairs`` is not a non-negative integer, ``parts`` is
        not one integer per face or ``box`` is not a finite box containing
        the referenced vertices.

    Notes
    -----
    Which pairs count depends on how many vertex *indices* the two faces share
    (positions are not compared, so an unwelded "triangle soup" reports all
    its touching neighbours: weld vertices first):

    * **No shared vertex**: the closed triangles intersect when they have any
      common point, touching and coplanar overlap included.
    * **One shared vertex** ``p``: they intersect when they have a common
      point other than ``p`` (farther than the tolerance from it): a fold or
      piercing near ``p``, an edge of one lying on the other, or, for
      coplanar faces, overlapping wedges at ``p``.
    * **Two shared vertices** (a shared edge): they intersect only when they
      fold onto each other, i.e. one face lies in the other's plane (within
      the tolerance) and the two opposite vertices are on the same side of
      the shared edge.  Any dihedral angle other than (close to) zero is not
      an intersection.
    * **Three shared vertices** (duplicate faces) and **degenerate faces**
      (a repeated index or zero area, see
      :func:`geotex.mesh.geometry.degenerate_faces`) are excluded: they are
      reported by their own checks.

    Predicates are evaluated in float64 on normalised coordinates (see the
    module docstring) with the tolerance ``REL_TOL * L + ABS_TOL``, where
    ``L`` is the longest edge of the two triangles.  A point within the
    tolerance of a triangle counts as on it, so exact contacts built in the
    input coordinates are found whatever their scale, and the answer does not
    change when the mesh is uniformly scaled or translated.

    The non-coplanar test uses the fact that each triangle meets the other's
    plane in a segment on the planes' common line, and two such segments
    overlap exactly when an endpoint of one lies in the other: every endpoint
    (a vertex in the plane, or an edge crossing it) is tested against the
    other triangle with edge functions.  Coplanar triangles are disjoint when
    the line of one of the six edges leaves the other triangle strictly
    outside; coplanar faces sharing a vertex compare their wedges at it.

    The work is vectorized numpy on chunks of bounded size (memory grows
    linearly with the mesh and the answer, not with the number of candidate
    pairs) and runs on up to four threads.  Faces with the same vertex set
    are tested once; pairs of faces around a vertex whose fan is provably
    embedded are not tested at all (see the module docstring).  Timings
    against libigl and pymeshlab: ``benchmarks/intersections.py``.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [2, 0, 0], [0, 2, 0],
    ...               [0.5, 0.5, -1], [0.5, 0.5, 1], [3, 3, 1]], float)
    >>> F = np.array([[0, 1, 2], [3, 4, 5]])
    >>> self_intersecting_pairs(V, F)
    array([[0, 1]])
    """
    V, F = as_mesh_arrays(V, F)
    if max_pairs is not None:
        if (isinstance(max_pairs, bool) or not isinstance(max_pairs, numbers.Integral)
                or max_pairs < 0):
            raise InputError(
                f"max_pairs must be a non-negative integer or None, got {max_pairs!r}")
        max_pairs = int(max_pairs)
    m = F.shape[0]
    if parts is not None:
        parts = np.asarray(parts)
        if parts.shape != (m,) or (m and not np.issubdtype(parts.dtype, np.integer)):
            raise InputError(f"parts must be one integer per face, shape ({m},), "
                             f"got {parts.dtype} {parts.shape}")
    empty = np.zeros((0, 2), dtype=np.int64)
    box = _box_argument(box)
    if m < 2 or max_pairs == 0:
        return empty
    unpaired = None
    if unpaired_vertices is not None:
        unpaired = np.asarray(unpaired_vertices)
        if unpaired.shape != (V.shape[0],) or unpaired.dtype != bool:
            raise InputError(f"unpaired_vertices must be one bool per vertex, shape "
                             f"({V.shape[0]},), got {unpaired.dtype} {unpaired.shape}")
    topo = None
    if F.size >= JIT_MIN_SIZE:
        topo = topology
        if topo is None and (unpaired is None or not distinct_faces):
            topo = edge_topology(F, V.shape[0])
        if unpaired is None:
            unpaired = unpaired_edge_vertices(topo, V.shape[0])
    else:
        parts = None                         # the part sweep is compiled only
    classes = None if distinct_faces else _duplicate_classes(F, topo)
    del topo, topology                       # not held through the search
    if classes is not None:                  # duplicate faces: solve on one per class
        first, cls = classes
        pairs = _distinct_pairs(V, F[first], max_pairs,
                                parts=None if parts is None else parts[first], box=box)
        pairs = _expanded(first[pairs], cls, max_pairs)
    else:
        pairs = _distinct_pairs(V, F, max_pairs, unpaired=unpaired, parts=parts, box=box)
    return pairs


def self_intersecting_pairs_touching(V, F, faces, *, box=None) -> np.ndarray:
    """Return the intersecting pairs of :func:`self_intersecting_pairs` with a face in ``faces``.

    Exactly the rows of ``self_intersecting_pairs(V, F)`` whose first or
    second face is in ``faces``, at a cost that grows with ``faces`` and the
    faces near them, not with the mesh: after a few vertices moved, the new
    crossings are the pairs touching the faces at those vertices.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    faces : array_like, (k,) int64
        Face indices (any order, repeats allowed).
    box : array_like, (2, 3) float64, optional
        The normalising box, as for :func:`self_intersecting_pairs`: the
        rows are those of ``self_intersecting_pairs(V, F, box=box)``.

    Returns
    -------
    numpy.ndarray, (p, 2) int64
        Face index pairs ``(i, j)``, ``i < j``, sorted, without repetition.

    Raises
    ------
    InputError
        If ``V``, ``F``, ``faces`` or ``box`` is malformed.

    Notes
    -----
    The predicates see the same numbers as in the full search: coordinates
    are normalised by the box of the whole mesh, and each face's plane, edge
    planes, tolerance and box depend on its own corners only.  The faces
    that may meet the chosen ones are found on a coarse grid of cells at
    least three times the largest face box of the mesh (a face whose box
    meets a chosen face's box has a corner in a cell next to one of that
    face's corners); only those are prepared.  The candidate pairs are the
    same compiled broad and narrow phase's, restricted to pairs with a
    chosen face.  Pairs around a vertex with a separated fan (module
    docstring, step 3), which the full search never tests because the
    narrow phase provably rejects them, are tested here; the answer is the
    same.  When faces with the same vertex set are among the prepared
    faces, the full search is run and its answer filtered.
    """
    V, F = as_mesh_arrays(V, F)
    sel = np.unique(np.asarray(faces, dtype=np.int64).ravel())
    m = F.shape[0]
    empty = np.zeros((0, 2), dtype=np.int64)
    if sel.size and (sel[0] < 0 or sel[-1] >= m):
        raise InputError(f"faces must be indices in [0, {m}), got {sel[0]} .. {sel[-1]}")
    box = _box_argument(box)
    if m < 2 or sel.size == 0:
        return empty
    Vn = _normalized(V, F, box)
    near = _faces_near(Vn, F, sel)
    sub = F[near]
    if _duplicate_classes(sub) is not None:          # rare: let the full search group them
        pairs = self_intersecting_pairs(V, F, box=box)
        keep = np.zeros(m, dtype=bool)
        keep[sel] = True
        return pairs[keep[pairs[:, 0]] | keep[pairs[:, 1]]]
    vids, local = np.unique(sub, return_inverse=True)
    sub = local.reshape(-1, 3)
    chosen = np.zeros(near.size, dtype=bool)
    chosen[np.searchsorted(near, sel)] = True
    workers = _workers()
    pool = ThreadPoolExecutor(max_workers=workers)
    found = []
    try:
        fd = _FaceData(Vn[vids], sub, mapper=pool.map)
        if fd.active.size >= 2 and chosen[fd.active].any():
            for hits in _in_order(pool, _touching_tasks(fd, chosen, mapper=pool.map),
                                  window=2 * workers):
                if hits.size:
                    found.append(hits)
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    if not found:
        return empty
    keys = np.sort(np.concatenate(found))
    k = sub.shape[0]
    return np.stack([near[keys // k], near[keys % k]], axis=1)   # ``near`` ascends: i < j


def self_intersecting_pairs_between(V, F, parts, *, side=None, within=None) -> np.ndarray:
    """Return the intersecting pairs of :func:`self_intersecting_pairs` between sides of parts.

    Exactly the rows of ``self_intersecting_pairs(V, F)`` whose two faces lie
    in parts on different sides (``side`` differs), and, with ``within``,
    those whose two faces lie in one part marked ``within``; the pairs of
    other parts (the whole of a mesh beside the few parts that matter, or
    every element's own faces) are not examined.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    parts : array_like, (m,) int
        Part of every face (for example its connected component).
    side : array_like, (m,) int or bool, optional
        Side of every face's part (the same for every face of a part;
        default: one side, no pairs between parts).
    within : array_like, (m,) bool, optional
        Whether the pairs within every face's part are wanted too (the same
        for every face of a part; default: none). One part ``within`` is
        the whole test of a small mesh (an element) without its grid and fan
        stages.

    Returns
    -------
    numpy.ndarray, (p, 2) int64
        Face index pairs ``(i, j)``, ``i < j``, sorted, without repetition.

    Raises
    ------
    InputError
        If ``V`` or ``F`` is malformed, or ``parts``, ``side`` or ``within``
        is not one value per face.

    Notes
    -----
    The predicates see the same numbers as in the full search (the same
    normalised coordinates and per-face data), and the pairs are those of the
    part sweep of ``self_intersecting_pairs(V, F, parts=parts)``, restricted
    to the wanted pairs of parts.  Pairs around a vertex with a separated fan
    (module docstring, step 3), which the full search never tests because
    the narrow phase provably rejects them, are tested here, so no fan is
    examined; the answer is the same.  A part of more than 4096 faces (a
    base beside the elements) is swept as runs of 256 faces, consecutive in
    Morton order of their boxes' centres, and the pairs of its runs are
    swept like pairs of parts (each pair of faces is still examined once):
    the grid's set-up over the whole mesh is not paid.  With faces of the
    same vertex set, the full search is run and its answer filtered.
    """
    V, F = as_mesh_arrays(V, F)
    m = F.shape[0]
    arrays = {"parts": parts, "side": side, "within": within}
    for name, value in arrays.items():
        if value is None:
            continue
        a = np.asarray(value)
        ok = a.dtype == bool or np.issubdtype(a.dtype, np.integer)
        if a.shape != (m,) or not ok or (name == "within" and a.dtype != bool):
            raise InputError(f"{name} must be one {'bool' if name == 'within' else 'integer'} "
                             f"per face, shape ({m},), got {a.dtype} {a.shape}")
        arrays[name] = a
    parts, side, within = arrays["parts"], arrays["side"], arrays["within"]
    if side is None:
        side = np.zeros(m, dtype=np.int64)
    empty = np.zeros((0, 2), dtype=np.int64)
    if m < 2:
        return empty

    def wanted(pairs):
        i, j = pairs[:, 0], pairs[:, 1]
        keep = side[i] != side[j]
        if within is not None:
            keep |= (parts[i] == parts[j]) & within[i]
        return pairs[keep]

    if _duplicate_classes(F) is not None:             # rare: the full search groups them
        return wanted(self_intersecting_pairs(V, F))
    # small meshes (an element and its surroundings) in this thread: starting
    # the pool's threads costs more than they would save
    pool = ThreadPoolExecutor(max_workers=_workers()) if m > _SERIAL_FACES else None
    mapper = map if pool is None else pool.map
    try:
        # (the sweep is compiled: so are the per-face data, the same numbers)
        faces = _FaceData(_normalized(V, F), F, mapper=mapper, compiled=True)
        keys = _part_sweep(faces, parts, mapper=mapper, side=side, within=within)
    finally:
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
    return np.stack([keys // m, keys % m], axis=1)


def offset_surface_pairs(Y, F, D, h, *, previous=None, box=None
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Intersecting face pairs of a surface ``(Y, F)`` together with its offset ``Y + h D``.

    The stacked mesh is ``Y`` and ``Y + h D`` with the faces ``F`` and
    ``F[:, ::-1] + len(Y)`` (the offset reversed); its pairs are those of
    :func:`self_intersecting_pairs`, with coordinates normalised by one box
    (``box``) that holds the offsets along all the directions a caller
    tries, so that after some directions change only the pairs touching
    the moved offset faces need a search.

    Parameters
    ----------
    Y : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    D : numpy.ndarray, (n, 3) float64
        Offset directions (unit, for the default ``box``).
    h : float
        Offset height.
    previous : tuple, optional
        The return value of an earlier call with the same ``Y`` and ``F`` and
        other directions (or a surface with some vertices moved): when the box
        is the same, only the pairs touching a face with a moved corner are
        searched again (:func:`self_intersecting_pairs_touching`) and the
        other pairs are kept, which is the same answer (a pair's predicates
        see only its two faces, in coordinates normalised by that box).
    box : array_like, (2, 3) float64, optional
        Box to normalise by (default: the box of ``Y``'s vertices in ``F``
        grown by ``h`` on every side, which holds their offsets along unit
        directions); grown to the stacked mesh's box where that is larger.

    Returns
    -------
    V : numpy.ndarray, (2 n, 3) float64
        The stacked vertices.
    pairs : numpy.ndarray, (k, 2) int64
        ``self_intersecting_pairs(V, stacked faces, box=box)``: rows below
        ``m`` are faces of ``(Y, F)``, the others offset faces (``m + f``).
    box : numpy.ndarray, (2, 3) float64
        The box the coordinates were normalised by.

    Raises
    ------
    InputError
        Malformed ``Y``, ``F``, ``D``, ``h`` or ``box``.
    """
    Y, F = as_mesh_arrays(Y, F)
    D = np.asarray(D, dtype=np.float64)
    if D.shape != Y.shape or not np.isfinite(D).all():
        raise InputError(f"D must be one finite direction per vertex, shape {Y.shape}, "
                         f"got {D.shape}")
    if not np.isfinite(h):
        raise InputError(f"h must be a finite height, got {h!r}")
    n = Y.shape[0]
    V = np.vstack([Y, Y + h * D])
    FF = np.vstack([F, F[:, ::-1] + n])
    used = np.zeros(V.shape[0], dtype=bool)
    used[FF.ravel()] = True
    U = V[used]
    if box is None:
        Yu = Y[used[:n]]
        box = np.stack([Yu.min(axis=0) - h, Yu.max(axis=0) + h])
    box = _box_argument(box)
    box = np.stack([np.minimum(box[0], U.min(axis=0)), np.maximum(box[1], U.max(axis=0))])
    if previous is not None:
        V0, pairs0, box0 = previous
        moved = (V != V0).any(axis=1) & used
        if not moved.any() and np.array_equal(box, box0):
            return V, pairs0, box0
        if np.array_equal(box, box0):
            changed = moved[FF].any(axis=1)
            keep = pairs0[~(changed[pairs0[:, 0]] | changed[pairs0[:, 1]])]
            new = self_intersecting_pairs_touching(V, FF, np.flatnonzero(changed), box=box)
            pairs = np.concatenate([keep, new])
            pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
            return V, pairs, box
    return V, self_intersecting_pairs(V, FF, box=box), box


def _faces_near(Vn, F, sel):
    """Sorted faces whose box (as the search inflates it) may meet a face of ``sel``'s.

    ``Vn``: the normalised coordinates (:func:`_normalized`).

    A superset, found on a grid of cells at least three times the largest
    face extent (plus the boxes' inflation) of the whole mesh: corners of
    two faces whose boxes meet are less than two such extents apart, so in
    the same or adjacent cells.  ``sel`` is included.
    """
    used = np.zeros(Vn.shape[0], dtype=bool)
    used[F.ravel()] = True
    ext = 0.0
    cols = [np.ascontiguousarray(F[:, k]) for k in range(3)]
    for axis in range(3):
        x = np.ascontiguousarray(Vn[:, axis])
        a, b, c = (np.take(x, col) for col in cols)
        hi = np.maximum(np.maximum(a, b), c)
        hi -= np.minimum(np.minimum(a, b), c)
        ext = max(ext, float(hi.max()))
        del a, b, c, hi
    lo = Vn[used].min(axis=0)
    span = float((Vn[used].max(axis=0) - lo).max())
    # inflation of a box: 2 tol + _BOX32_PAD plus float32 rounding, far below 2**-18
    # in normalised coordinates (extent below 2)
    cell = max(3.0 * (ext + 2.0 ** -18), span / 256.0, 2.0 ** -18)
    cells = np.floor((Vn - lo) / cell).astype(np.int64)
    np.clip(cells, 0, None, out=cells)               # unreferenced vertices: anywhere
    dims = cells[used].max(axis=0) + 1
    np.minimum(cells, dims - 1, out=cells)
    grid = np.zeros(tuple(int(d) for d in dims), dtype=bool)
    mark = np.unique(F[sel].ravel())
    grid[cells[mark, 0], cells[mark, 1], cells[mark, 2]] = True
    for axis in range(3):                            # dilate by one cell
        g = np.moveaxis(grid, axis, 0)
        g[1:] |= g[:-1].copy()
        g[:-1] |= g[1:].copy()
    hot = grid[cells[:, 0], cells[:, 1], cells[:, 2]] & used
    return np.flatnonzero(hot[cols[0]] | hot[cols[1]] | hot[cols[2]])


def _distinct_pairs(V, F, max_pairs, *, unpaired=None, parts=None, box=None):
    """:func:`self_intersecting_pairs` for faces with distinct vertex sets
    (``unpaired``: their unpaired-edge vertices, when known; ``parts``, ``box``: see there)."""
    m = F.shape[0]
    empty = np.zeros((0, 2), dtype=np.int64)
    workers = _workers()
    pool = ThreadPoolExecutor(max_workers=workers)
    try:
        faces = _FaceData(_normalized(V, F, box), F, mapper=pool.map)
        if faces.active.size < 2:
            return empty
        faces.separated = _separated_fans(faces, mapper=pool.map, unpaired=unpaired)
        faces.mask_unseparated()
        faces.corner_columns = None             # not read again: 12 bytes per face less
        del unpaired
        found = []
        count = 0
        swept = None if parts is None else _part_sweep(faces, parts, mapper=pool.map)
        if swept is not None:
            found.append(swept)
            count = swept.size
        for hits in (() if swept is not None else
                     _in_order(pool, _pair_tasks(faces, mapper=pool.map),
                               window=2 * workers)):
            if hits.size:
                found.append(hits)
                count += hits.size
                if max_pairs is not None and count >= max_pairs:
                    break
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
    if not found:
        return empty
    keys = np.sort(np.concatenate(found))
    if max_pairs is not None:
        keys = keys[:max_pairs]
    return np.stack([keys // m, keys % m], axis=1)


def _workers() -> int:
    try:
        n = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        n = os.cpu_count() or 1
    return max(1, min(n, _MAX_WORKERS))


def _in_order(pool, tasks, *, window: int):
    """Run callables on ``pool``, at most ``window`` at a time; yield results in order."""
    pending = collections.deque()
    try:
        for task in tasks:
            pending.append(pool.submit(task))
            if len(pending) >= window:
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()
    finally:
        for future in pending:
            future.cancel()


# ---------------------------------------------------------------------------
# duplicate faces


def _duplicate_classes(F: np.ndarray, topo=None):
    """Group the faces by vertex set; ``None`` when all sets differ.

    With the edge topology ``topo`` and no edge of more than two faces nor a
    repeated index, two faces with one vertex set are each other's
    neighbours across all three edges: that is looked up instead of sorting.

    Returns
    -------
    first : (K,) int64
        Ascending index of the first face of each class.
    cls : (m,) int64
        Class of every face (a row of ``first``).
    """
    if (topo is not None and not (topo.face_count > 2).any()
            and not ((F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])).any()):
        if F.size >= JIT_MIN_SIZE and topo.half_order is not None:
            if not has_twin_faces(topo):
                return None
        else:
            ef = topo.edge_faces()[topo.half_to_edge]            # (3m, 2)
            own = np.repeat(np.arange(F.shape[0]), 3)
            other = np.where(ef[:, 0] == own, ef[:, 1], ef[:, 0]).reshape(-1, 3)
            if not ((other[:, 0] >= 0) & (other[:, 0] == other[:, 1])
                    & (other[:, 1] == other[:, 2])).any():
                return None
    lo = F.min(axis=1)
    hi = F.max(axis=1)
    mid = F.sum(axis=1) - lo - hi
    bits = max(1, int(hi.max()).bit_length())
    if 3 * bits <= 63:
        key = (lo << (2 * bits)) | (mid << bits) | hi
        s = np.sort(key)
        if not np.any(s[1:] == s[:-1]):
            return None
        del s
        _, first, cls = np.unique(key, return_index=True, return_inverse=True)
    else:
        _, first, cls = np.unique(np.stack([lo, mid, hi], axis=1), axis=0,
                                  return_index=True, return_inverse=True)
        if first.size == F.shape[0]:
            return None
    order = np.argsort(first)                   # number classes by first face
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return first[order], rank[cls.ravel()]


def _expanded(pairs: np.ndarray, cls: np.ndarray, max_pairs) -> np.ndarray:
    """Pairs of class representatives -> pairs of all their members, sorted.

    ``pairs`` holds face indices of the first face of classes (``i < j``);
    every member of one class of a pair meets every member of the other.  The
    rows are produced in sorted order (no sort over the output): for each
    face ``a``, the sorted members of all classes meeting ``a``'s class,
    after ``a``.  Work and memory are linear in the output size.
    """
    m = cls.size
    if pairs.shape[0] == 0:
        return pairs
    K = int(cls.max()) + 1
    members = np.argsort(cls, kind="stable")   # by class, then face
    size = np.bincount(cls, minlength=K)
    start = np.cumsum(size) - size
    c = cls[pairs[:, 0]]
    d = cls[pairs[:, 1]]
    src = np.concatenate([c, d])
    dst = np.concatenate([d, c])
    n = size[dst]
    off = np.cumsum(n) - n
    # partner lists: key = class * m + member of a class meeting it, sorted
    key = members[np.repeat(start[dst] - off, n) + np.arange(int(n.sum()))]
    key += np.repeat(src, n) * m
    key.sort()
    bounds = np.searchsorted(key, np.arange(K + 1, dtype=np.int64) * m)
    own = cls * m
    pos = np.searchsorted(key, own + np.arange(m), side="right")
    key -= np.repeat(np.arange(K, dtype=np.int64) * m, np.diff(bounds))   # -> face
    count = bounds[cls + 1] - pos
    cum = np.cumsum(count)
    if max_pairs is not None and cum[-1] > max_pairs:
        r = int(np.searchsorted(cum, max_pairs))
        count[r] -= cum[r] - max_pairs
        count[r + 1:] = 0
        cum = np.cumsum(count)
    total = int(cum[-1])
    out = np.empty((total, 2), dtype=np.int64)
    out[:, 0] = np.repeat(np.arange(m), count)
    at = np.arange(total)
    at += np.repeat(pos - (cum - count), count)
    np.take(key, at, out=out[:, 1])
    return out


# ---------------------------------------------------------------------------
# preparation


def _box_argument(box):
    """``box`` of :func:`self_intersecting_pairs` as a ``(2, 3)`` float64 array, or None."""
    if box is None:
        return None
    b = np.asarray(box, dtype=np.float64)
    if b.shape != (2, 3) or not np.isfinite(b).all() or (b[0] > b[1]).any():
        raise InputError(f"box must be a finite (2, 3) array of a low and a high corner, "
                         f"got {np.shape(box)}")
    return b


def _normalized(V: np.ndarray, F: np.ndarray, box=None) -> np.ndarray:
    """Return ``V`` centred on the box of the referenced vertices (or on ``box``,
    which must contain them), the box's largest extent in [1, 2)."""
    used = np.zeros(V.shape[0], dtype=bool)
    used[F.ravel()] = True
    U = V[used]
    lo, hi = U.min(axis=0), U.max(axis=0)
    del U
    if box is not None:
        if (lo < box[0]).any() or (hi > box[1]).any():
            raise InputError(f"box must contain the referenced vertices, got {box.tolist()} "
                             f"around vertices spanning {[lo.tolist(), hi.tolist()]}")
        lo, hi = box[0], box[1]
    half = float(np.max(0.5 * hi - 0.5 * lo))
    exponent = int(np.frexp(half)[1]) if half > 0 else 0
    # exact scaling (half-extent in [0.5, 1)): the box of the scaled rows is the
    # scaled box
    shift = 0.5 * np.ldexp(lo, -exponent) + 0.5 * np.ldexp(hi, -exponent)
    W = np.ldexp(V, -exponent)
    W -= shift
    return W


class _FaceData:
    """Per-face arrays used by both phases (normalised coordinates).

    Attributes
    ----------
    V : (n, 3) float64
        Normalised vertex positions.
    F : (m, 3) int64
    plane : (m, 4) float64
        Unit normal and plane offset ``n . v0``.
    tol : (m,) float64
        ``REL_TOL * longest edge + ABS_TOL``.
    E : (m, 12) float64
        Per edge ``k`` (from ``v_k`` to ``v_k+1``): the unit vector ``w_k``
        in the face's plane, normal to the edge and pointing into the face,
        and ``w_k . v_k``; ``w_k . x - w_k . v_k`` is the signed distance of
        the projection of ``x`` to the edge's line, positive inside.
    box32 : (m, 6) float32
        Bounding box (low corner, high corner) inflated by twice the
        tolerance, and widened to cover the float32 rounding.
    active : (a,) int64
        Non-degenerate faces.
    masked : bool
        Whether :meth:`mask_unseparated` has set ``masked_rows``.
    masked_rows : (m, 3) int array
        Per corner the vertex id, negative where the fan is not separated
        (``(0, 3)`` until set).
    """

    def __init__(self, Vn: np.ndarray, F: np.ndarray, *, mapper=map, compiled=None):
        # compiled: the compiled loops whatever the size (default: from JIT_MIN_SIZE)
        m = F.shape[0]
        self.V = Vn
        self.F = np.ascontiguousarray(F)
        self.plane = np.empty((m, 4))
        self.tol = np.empty(m)
        self.E = np.empty((m, 12))
        self.box32 = np.empty((m, 6), dtype=np.float32)
        bad = np.empty(m, dtype=bool)
        blocks = range(0, m, _FACE_BLOCK)
        if F.size >= JIT_MIN_SIZE if compiled is None else compiled:
            fill = partial(_face_loops, Vn, self.F, self.plane, self.tol, self.E, self.box32, bad)
            for _ in mapper(lambda s: fill(s, min(s + _FACE_BLOCK, m)), blocks):
                pass
        else:
            for _ in mapper(lambda s: self._fill(bad, s, min(s + _FACE_BLOCK, m)), blocks):
                pass
        self.active = np.flatnonzero(~bad)
        self.separated = None
        dtype = np.int32 if Vn.shape[0] < 2 ** 31 else np.int64
        self.corner_columns = [F[:, k].astype(dtype) for k in range(3)]
        self.masked = False
        self.masked_rows = np.empty((0, 3), dtype=np.int32)

    def active_mask(self) -> np.ndarray:
        """Boolean over the faces: non-degenerate (``active`` as a mask)."""
        mask = np.zeros(self.F.shape[0], dtype=bool)
        mask[self.active] = True
        return mask

    def mask_unseparated(self):
        """Set ``masked_rows``: vertex ids, those of unseparated fans negative.

        Every corner at a vertex outside ``separated`` gets its own negative
        id, so two faces have an equal masked id exactly when they share a
        vertex whose fan is separated.
        """
        m = self.F.shape[0]
        dtype = np.int32 if 3 * m < 2 ** 31 else np.int64
        self.masked_rows = np.empty((m, 3), dtype=dtype)
        for k, col in enumerate(self.corner_columns):
            own = -(3 * np.arange(m, dtype=np.int64) + k) - 1
            self.masked_rows[:, k] = np.where(self.separated[col], col, own)
        self.masked = True

    def _fill(self, bad, s, e):
        F = self.F[s:e]
        P = np.take(self.V, F.ravel(), axis=0).reshape(-1, 9)
        x0, y0, z0, x1, y1, z1, x2, y2, z2 = (P[:, k] for k in range(9))
        edges = ((x1 - x0, y1 - y0, z1 - z0), (x2 - x1, y2 - y1, z2 - z1),
                 (x0 - x2, y0 - y2, z0 - z2))
        (ax, ay, az), _, (cx, cy, cz) = edges
        nx = az * cy - ay * cz                  # e0 x (v2 - v0) = e0 x (-e2)
        ny = ax * cz - az * cx
        nz = ay * cx - ax * cy
        double_area = np.sqrt(nx * nx + ny * ny + nz * nz)
        length2 = [ex * ex + ey * ey + ez * ez for ex, ey, ez in edges]
        longest2 = np.maximum(np.maximum(length2[0], length2[1]), length2[2])
        degenerate = ~(double_area > _DEGENERATE_REL_TOL * longest2)
        degenerate |= (F[:, 0] == F[:, 1]) | (F[:, 1] == F[:, 2]) | (F[:, 2] == F[:, 0])
        bad[s:e] = degenerate
        inv = np.divide(1.0, double_area, out=np.zeros_like(double_area), where=~degenerate)
        plane = self.plane[s:e]
        plane[:, 0] = nx * inv
        plane[:, 1] = ny * inv
        plane[:, 2] = nz * inv
        plane[:, 3] = plane[:, 0] * x0 + plane[:, 1] * y0 + plane[:, 2] * z0
        tol = REL_TOL * np.sqrt(longest2) + ABS_TOL
        self.tol[s:e] = tol
        E = self.E[s:e]
        ux, uy, uz = plane[:, 0], plane[:, 1], plane[:, 2]
        for k, (ex, ey, ez) in enumerate(edges):
            inv_len = np.divide(1.0, np.sqrt(length2[k]), out=np.zeros_like(tol),
                                where=~degenerate)
            wx = (uy * ez - uz * ey) * inv_len      # n x e_k points into the face
            wy = (uz * ex - ux * ez) * inv_len
            wz = (ux * ey - uy * ex) * inv_len
            px, py, pz = P[:, 3 * k], P[:, 3 * k + 1], P[:, 3 * k + 2]
            E[:, 4 * k] = wx
            E[:, 4 * k + 1] = wy
            E[:, 4 * k + 2] = wz
            E[:, 4 * k + 3] = wx * px + wy * py + wz * pz
        pad = 2.0 * tol + _BOX32_PAD
        box = self.box32[s:e]
        for axis, (u0, u1, u2) in enumerate(((x0, x1, x2), (y0, y1, y2), (z0, z1, z2))):
            box[:, axis] = np.minimum(np.minimum(u0, u1), u2) - pad
            box[:, 3 + axis] = np.maximum(np.maximum(u0, u1), u2) + pad


# ---------------------------------------------------------------------------
# vertex fans that cannot intersect


def _separated_fans(faces: _FaceData, *, mapper=map, unpaired=None) -> np.ndarray:
    """Vertices whose faces provably meet only along their shared edges.

    Returns a boolean array over the vertices.  A vertex ``p`` qualifies
    when its faces form one closed, consistently oriented disc (every edge of
    the mesh at ``p`` is used exactly once in each direction, no degenerate
    face at ``p``) that is a height field over the plane normal to the mean
    face normal ``n`` (``n . n_f >= c > 0`` for every face ``f`` at ``p``),
    winding once around ``p`` (the projected face angles sum to ``2 pi``),
    with a margin far above the tolerance.  The narrow phase then reports no
    pair of faces sharing ``p`` (for the proof see ``docs/architecture.md``,
    "Self-intersections"):

    * with ``D_f`` the projected angle of face ``f`` at ``p``,
      ``mu = min_f min(D_f, pi - D_f) / 2`` and ``l`` the shortest edge at
      ``p``, two faces sharing only ``p`` are split by a plane through ``p``
      (containing ``n``) with their free corners at least ``c l sin(mu)``
      from it, and two faces sharing an edge lie on either side of the plane
      through that edge and ``n`` by at least as much;
    * the narrow phase's tolerant predicates accept a point of one face only
      within ``t (1 + 1/s)`` of the other face's cone at ``p`` (``t`` the
      largest tolerance, ``s`` the smallest ``sin(alpha_f / 2)``,
      ``alpha_f`` the face angle at ``p``), and every candidate point of a
      face is at least ``q c l sin(mu)`` from the splitting plane (``q`` the
      smallest height-from-``p`` / longest edge); the coplanar wedge test
      accepts a corner within ``t (1 + 1/s + 2 L rho)`` of the other cone
      (``L`` the longest edge, ``rho`` the largest ``(|a - p| + |b - p|) /
      |(a - p) x (b - p)|``: how far a face within ``t`` of the other's
      plane can tilt out of it);
    * so ``c l sin(mu) >= 8 t max((1 + 1/s) / q, 1 + 1/s + 2 L rho)`` (a
      factor 8 over the bound, for rounding) excludes every pair.
    """
    V, F = faces.V, faces.F
    n, m = V.shape[0], F.shape[0]
    bits = max(1, int(n - 1).bit_length())
    if 2 * bits + 1 > 63:
        return np.zeros(n, dtype=bool)
    good = np.ones(n, dtype=bool)
    inactive = np.ones(m, dtype=bool)
    inactive[faces.active] = False
    good[F[inactive].ravel()] = False
    # every edge used exactly once in each direction
    if unpaired is not None or F.size >= JIT_MIN_SIZE:
        if unpaired is None:
            unpaired = unpaired_edge_vertices(edge_topology(F, n), n)
        good &= ~unpaired
    else:
        u = F.ravel()
        v = F[:, [1, 2, 0]].ravel()
        key = (np.minimum(u, v) << (bits + 1)) | (np.maximum(u, v) << 1) | (u > v)
        key.sort()
        edge = key >> 1
        starts = np.flatnonzero(np.r_[True, edge[1:] != edge[:-1]])
        length = np.diff(np.r_[starts, key.size])
        ok_edge = length == 2
        ok_edge[ok_edge] = (((key[starts[ok_edge]] & 1) == 0)
                            & ((key[starts[ok_edge] + 1] & 1) == 1))
        bad = edge[starts[~ok_edge]]
        good[bad >> bits] = False
        good[bad & ((1 << bits) - 1)] = False
        del key, edge, starts, length, ok_edge, bad
    # per corner, in face order (corner k of a face is at vertex F[:, k]);
    # per-vertex minima, maxima and sums by scattering
    cols = faces.corner_columns
    # the face normals one axis at a time (kept only for the numpy path's terms)
    unit, N = [], []
    count = None
    if F.size >= JIT_MIN_SIZE:
        # compiled: the sums of np.bincount per corner column, in its order of
        # additions, with the vertices split between the threads
        Ns = np.empty((3, n))
        count = np.empty(n, np.int64)
        bounds = _pieces(n, _workers())
        _each(mapper, bounds, lambda k, s, e: _normal_sums(F, faces.plane, s, e, Ns, count))
        N = list(Ns)
    for i in range(3 if F.size < JIT_MIN_SIZE else 0):
        x = np.ascontiguousarray(faces.plane[:, i])
        N.append(sum(np.bincount(c, weights=x, minlength=n) for c in cols))
        unit.append(x)
    with np.errstate(divide="ignore", invalid="ignore"):
        norm = np.sqrt(N[0] * N[0] + N[1] * N[1] + N[2] * N[2])
        N = [x / norm for x in N]
    cos_min = np.full(n, np.inf)
    total = np.zeros(n)
    spread = np.full(n, np.inf)
    shortest = np.full(n, np.inf)
    sin_min = np.full(n, np.inf)
    q_min = np.full(n, np.inf)
    rho = np.zeros(n)
    longest = np.zeros(n)
    t = np.zeros(n)
    acc = (cos_min, total, spread, shortest, sin_min, q_min, rho, longest, t)
    if F.size >= JIT_MIN_SIZE:
        # compiled: terms and scatter in one loop, vertices split between two
        # threads (each vertex gets its terms in the numpy path's order)
        Nv = np.ascontiguousarray(np.stack(N, axis=1))
        N = None                                # only Nv is read from here
        cuts = [0, n // 2, n]
        for _ in mapper(lambda k: _fan_term_loops(V, F, faces.plane, faces.tol, faces.active_mask(),
                                                  Nv, cuts[k], cuts[k + 1], _FACE_BLOCK, *acc),
                        range(2)):
            pass
        del Nv
    starts = range(0, m, _FACE_BLOCK) if F.size < JIT_MIN_SIZE else range(0)
    vcols = [np.ascontiguousarray(V[:, i]) for i in range(3)] if starts else None
    parts = mapper(
        lambda s: _corner_terms(faces, vcols, N, unit, s, min(s + _FACE_BLOCK, m)), starts)
    with np.errstate(invalid="ignore", over="ignore"):       # NaN: degenerate faces
        for s, part in zip(starts, parts):                   # scatter in block order
            tol = faces.tol[s:s + _FACE_BLOCK]
            for col, (cos_n, sector, length, rim, half_sin, q, r, big) in zip(cols, part):
                c = col[s:s + _FACE_BLOCK]
                if F.size >= JIT_MIN_SIZE:
                    _scatter_fan_terms(c, cos_n, sector, rim, length, half_sin, q, r, big, tol,
                                       cos_min, total, spread, shortest, sin_min, q_min, rho,
                                       longest, t)
                    continue
                np.minimum.at(cos_min, c, cos_n)
                np.add.at(total, c, sector)
                np.minimum.at(spread, c, rim)
                np.minimum.at(shortest, c, length)
                np.minimum.at(sin_min, c, half_sin)
                np.minimum.at(q_min, c, q)
                np.maximum.at(rho, c, r)
                np.maximum.at(longest, c, big)
                np.maximum.at(t, c, tol)
        if count is None:
            count = sum(np.bincount(c, minlength=n) for c in cols)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        margin = cos_min * shortest * np.sin(0.5 * spread)
        reach = np.maximum((1.0 + 1.0 / sin_min) / q_min,
                           1.0 + 1.0 / sin_min + 2.0 * longest * rho)
        out = (good & (norm > 0) & (count >= 3) & (cos_min > 0) & (spread > 0)
               & (np.abs(total - 2.0 * np.pi) < 1e-6)
               & (margin >= _FAN_SAFETY * t * reach))
    return out


def _corner_terms(faces: _FaceData, vcols, N, unit, s: int, e: int):
    """Per corner ``k`` of faces ``s .. e - 1``: the terms of :func:`_separated_fans`.

    ``vcols``, ``N`` and ``unit`` are the vertex positions, the vertex
    normals and the face normals, one array per axis.

    Returns, per corner, ``(cos_n, sector, length, rim, half_sin, q, rho,
    longest)``: ``n . n_f``, the angle of the face at the corner projected
    along the vertex's ``n``, the length of the edge leaving the corner,
    ``min(sector, pi - sector)``, ``sin(alpha / 2)`` (``alpha`` the face
    angle there), height from the corner / longest edge, ``(|a - p| + |b -
    p|) / |(a - p) x (b - p)|`` and the longest edge.
    """
    F = faces.F[s:e]
    X = [[np.take(vcols[i], F[:, k]) for i in range(3)] for k in range(3)]
    # edge k from corner k to corner k + 1
    E = [[X[(k + 1) % 3][i] - X[k][i] for i in range(3)] for k in range(3)]
    del X
    length = [np.sqrt(x * x + y * y + z * z) for x, y, z in E]
    longest = np.maximum(np.maximum(length[0], length[1]), length[2])
    nf = [x[s:e] for x in unit]
    ax, ay, az = E[0]
    bx, by, bz = E[2]
    cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    double_area = np.abs(cx * nf[0] + cy * nf[1] + cz * nf[2])   # |e0 x e2|
    out = []
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for k in range(3):
            p = faces.F[s:e, k]
            Np = [np.take(x, p) for x in N]
            cos_n = Np[0] * nf[0] + Np[1] * nf[1] + Np[2] * nf[2]
            A, B = E[k], E[(k + 2) % 3]                  # corner's edges: A and -B
            AB = -(A[0] * B[0] + A[1] * B[1] + A[2] * B[2])
            NA = Np[0] * A[0] + Np[1] * A[1] + Np[2] * A[2]
            NB = -(Np[0] * B[0] + Np[1] * B[1] + Np[2] * B[2])
            # the angle at the corner of the face projected along n: in
            # (0, pi) when cos_n > 0 (n . (A x -B) = double_area * cos_n)
            sector = np.arctan2(double_area * cos_n, AB - NA * NB)
            q = double_area / (length[(k + 1) % 3] * longest)   # height / longest
            la, lb = length[k], length[(k + 2) % 3]
            half_sin = np.sqrt(np.maximum(0.5 - 0.5 * AB / (la * lb), 0.0))
            out.append((cos_n, sector, la, np.minimum(sector, np.pi - sector), half_sin,
                        q, (la + lb) / double_area, longest))
    return out


# ---------------------------------------------------------------------------
# broad phase


def _pair_tasks(faces: _FaceData, *, mapper=map):
    """Yield callables; each returns the intersecting pairs of one chunk as keys.

    Over all tasks, every pair of active faces whose boxes overlap is
    examined exactly once.  A key is ``i * m + j`` with ``i < j``.
    ``mapper``: where the compiled grids run their pieces (the pool).
    """
    cell0, level = _grid_levels(faces)
    for lev in np.unique(level):
        cell = cell0 * _LEVEL_RATIO ** lev
        cur = np.flatnonzero(level == lev)
        low = np.flatnonzero(level < lev)
        yield from _level_tasks(faces, cell, cur, _near(faces, cur, low, mapper=mapper),
                                mapper=mapper)


def _touching_tasks(faces: _FaceData, chosen: np.ndarray, *, mapper=map):
    """:func:`_pair_tasks` for the pairs with at least one face in ``chosen``.

    ``chosen`` is a boolean over the faces.  A chosen face of level ``L`` is
    paired on level ``L``'s grid with the chosen faces of its level and below
    and with every other face (of any level: larger ones simply cover more
    cells), so every pair of overlapping boxes with a chosen face is examined
    exactly once.
    """
    cell0, level = _grid_levels(faces)
    mine = chosen[faces.active]
    for lev in np.unique(level[mine]):
        cell = cell0 * _LEVEL_RATIO ** lev
        cur = np.flatnonzero(mine & (level == lev))
        low = np.flatnonzero(~mine | (level < lev))
        yield from _level_tasks(faces, cell, cur, _near(faces, cur, low, mapper=mapper),
                                mapper=mapper)


def _near(faces, cur, low, *, mapper=map):
    """The rows of ``low`` whose boxes meet the bounding box of the boxes ``cur``
    (rows of ``faces.active``); ``low`` in pieces on ``mapper``."""
    if low.size:
        near = np.empty(low.size, dtype=bool)
        act, box32 = faces.active, faces.box32
        rows = act[cur]
        lo = [box32[rows, axis].min() for axis in range(3)]
        hi = [box32[rows, 3 + axis].max() for axis in range(3)]
        del rows

        def piece(k, s, e):
            rows = act[low[s:e]]
            keep = np.ones(e - s, dtype=bool)
            for axis in range(3):
                keep &= (box32[rows, axis] <= hi[axis]) & (box32[rows, 3 + axis] >= lo[axis])
            near[s:e] = keep

        _each(mapper, _pieces(low.size, _workers()), piece)
        low = low[near]
    return low


def _active_boxes(faces):
    """The active faces' boxes, one contiguous float32 array per bound (low x, y, z,
    high x, y, z): only the numpy grid reads them (the compiled one reads ``box32``)."""
    return [np.ascontiguousarray(faces.box32[faces.active, k]) for k in range(6)]


def _grid_levels(faces: _FaceData):
    """The finest cell and each active face's level."""
    extent = None                                # largest side of each box, float32
    for axis in range(3):
        side = faces.box32[faces.active, 3 + axis] - faces.box32[faces.active, axis]
        extent = side if extent is None else np.maximum(extent, side)
    del side
    extent = extent.astype(np.float64)
    cell0 = _CELL_RATIO * float(np.quantile(extent, _BASE_QUANTILE))
    # level L: cells of cell0 * 2**L, faces up to twice that size (<= 3 cells
    # per axis); an even mesh has all its faces on level 0
    with np.errstate(divide="ignore"):
        level = np.ceil(np.log(extent / (2.0 * cell0)) / np.log(_LEVEL_RATIO))
    level = np.maximum(level, 0).astype(np.int64)
    while True:                                  # fix rounding of the logarithm
        short = extent > 2.0 * cell0 * _LEVEL_RATIO ** level
        if not short.any():
            break
        level[short] += 1
    return cell0, level


def _cell_bounds(box, rows, cell):
    """First and last grid cell covered by boxes ``rows``: two lists of 3 int64 arrays.

    The same monotone computation is used for every box, so boxes that
    overlap always have ``lo_j <= hi_i`` in cell coordinates too.
    """
    lo, hi = [], []
    for axis in range(3):
        for out, col in ((lo, box[axis]), (hi, box[3 + axis])):
            out.append(np.floor(col[rows].astype(np.float64) / cell).astype(np.int64))
    return lo, hi


def _offsets(lo, hi):
    """Yield ``(dx, dy, dz, idx)``: boxes ``idx`` cover the cell ``lo + (dx, dy, dz)``."""
    span = [h - l for l, h in zip(lo, hi)]
    n = lo[0].size
    for dx in range(int(span[0].max()) + 1):
        mx = span[0] >= dx
        for dy in range(int(span[1].max()) + 1):
            mxy = mx & (span[1] >= dy)
            for dz in range(int(span[2].max()) + 1):
                if dx == dy == dz == 0:
                    yield 0, 0, 0, np.arange(n)
                else:
                    idx = np.flatnonzero(mxy & (span[2] >= dz))
                    if idx.size:
                        yield dx, dy, dz, idx


def _corner_mask(dx, dy, dz):
    return np.uint8((dx == 0) | (dy == 0) << 1 | (dz == 0) << 2)


def _packed_entries(lo, hi, lowbits, rows, flag, cmin, size, row_bits):
    """Grid entries as packed keys ``(cell, flag, row, corner bits)``.

    The corner bits of an entry tell on which axes its cell is the box's
    lowest cell (``lowbits`` clears the axes where the true lowest cell was
    clipped away).
    """
    shift = row_bits + 3
    key = ((lo[0] - cmin[0]) * size[1] + (lo[1] - cmin[1])) * size[2] + (lo[2] - cmin[2])
    base = ((key * 2 + flag) << shift) | (rows.astype(np.int64) << 3)
    del key
    out = []
    for dx, dy, dz, idx in _offsets(lo, hi):
        step = ((dx * size[1] + dy) * size[2] + dz) << (shift + 1)
        out.append((base[idx] + step) | (lowbits[idx] & _corner_mask(dx, dy, dz)))
    return np.concatenate(out)


def _coordinate_entries(lo, hi, lowbits, rows):
    """Grid entries as ``(rows, corner bits, (E, 3) cell coordinates)``."""
    r, f, c = [], [], []
    for dx, dy, dz, idx in _offsets(lo, hi):
        r.append(rows[idx])
        f.append(lowbits[idx] & _corner_mask(dx, dy, dz))
        c.append(np.stack([lo[0][idx] + dx, lo[1][idx] + dy, lo[2][idx] + dz], axis=1))
    return np.concatenate(r), np.concatenate(f), np.concatenate(c)


def _fits(size, shift) -> bool:
    """Whether cell keys of a grid of ``size`` cells pack into an int64 key."""
    return float(size[0]) * size[1] * size[2] * 2 < 2.0 ** (_KEY_BITS - shift)


def _level_tasks(faces, cell, cur, low, *, mapper=map):
    """Sort one level's grid entries by cell and yield its pair tasks.

    ``cur`` and ``low`` are rows of ``faces.active``: the faces of this level
    and the smaller faces that may meet them.  ``mapper`` runs the pieces of
    the compiled grid (the pool; the same grid whatever runs them).
    """
    act = faces.active
    row_bits = max(1, int(act.size - 1).bit_length())
    shift = row_bits + 3
    if 3 * act.size >= JIT_MIN_SIZE and act.size < 2 ** 31:
        # compiled: the entries, their sort and the pair counts in loops (the
        # numpy path below spends most of its time in temporaries)
        ok, first, face, counts, cuts = _level_grid(faces.box32, act, cur, low, cell, row_bits,
                                                    _KEY_BITS, _PAIR_CHUNK, _OCC_CELLS,
                                                    mapper=mapper, split=_workers())
        if ok:
            level = (counts, first, face)
            for k in range(cuts.size - 1):
                yield partial(_pair_task, faces, level, int(cuts[k]), int(cuts[k + 1]))
            return
    box = _active_boxes(faces)
    lo, hi = _cell_bounds(box, cur, cell)
    cmin = [int(x.min()) for x in lo]
    cmax = [int(x.max()) for x in hi]
    size = [b - a + 1 for a, b in zip(cmin, cmax)]
    values = None
    if not _fits(size, shift):
        # far-apart clusters: number the cells in use on each axis instead
        # (consecutive cells keep consecutive numbers)
        values = []
        for axis in range(3):
            span = hi[axis] - lo[axis]
            used = np.unique(np.concatenate(
                [lo[axis][span >= d] + d for d in range(int(span.max()) + 1)]))
            values.append(used)
            lo[axis] = np.searchsorted(used, lo[axis])
            hi[axis] = np.searchsorted(used, hi[axis])
        cmin = [0, 0, 0]
        size = [v.size for v in values]
        cmax = [n - 1 for n in size]
    all7 = np.full(cur.size, 7, dtype=np.uint8)
    if low.size:
        llo, lhi = _cell_bounds(box, low, cell)
        keep = np.ones(low.size, dtype=bool)
        lowbits = np.zeros(low.size, dtype=np.uint8)
        for axis in range(3):
            if values is None:
                exact = llo[axis] >= cmin[axis]     # true lowest cell is in range
                np.maximum(llo[axis], cmin[axis], out=llo[axis])
                np.minimum(lhi[axis], cmax[axis], out=lhi[axis])
            else:
                used = values[axis]
                first = np.searchsorted(used, llo[axis])    # first used cell >= lo
                exact = used[np.minimum(first, used.size - 1)] == llo[axis]
                llo[axis] = first
                lhi[axis] = np.searchsorted(used, lhi[axis], side="right") - 1
            lowbits |= exact.astype(np.uint8) << axis
            keep &= llo[axis] <= lhi[axis]
        sel = np.flatnonzero(keep)
        low = low[sel]
        llo = [x[sel] for x in llo]
        lhi = [x[sel] for x in lhi]
        lowbits = lowbits[sel]
    index = np.int32 if act.size < 2 ** 31 else np.int64
    if _fits(size, shift):
        packed = _packed_entries(lo, hi, all7, cur, 0, cmin, size, row_bits)
        if low.size:
            lpacked = _packed_entries(llo, lhi, lowbits, low, 1, cmin, size, row_bits)
            # keep only entries in cells that hold a current-level face
            cells = np.unique(packed >> (shift + 1))
            key = lpacked >> (shift + 1)
            pos = np.minimum(np.searchsorted(cells, key), cells.size - 1)
            packed = np.concatenate([packed, lpacked[cells[pos] == key]])
            del lpacked, key, pos, cells
        del lo, hi, all7                            # only the packed keys from here
        if low.size:
            del llo, lhi, lowbits
        if packed.size >= JIT_MIN_SIZE:             # by cell, then current level first
            packed = _sorted_by_high_bits_inplace(packed, shift,
                                                  int(packed.max() >> shift).bit_length())
        else:
            packed.sort()
        first = (packed & 7).astype(np.uint8)
        rows = ((packed >> 3) & ((1 << row_bits) - 1)).astype(index)
        is_low = ((packed >> shift) & 1).astype(bool)
        packed >>= shift + 1
        cellkey = packed
        del packed
    else:                                           # huge grid: dense cell ids
        r1, f1, c1 = _coordinate_entries(lo, hi, all7, cur)
        if low.size:
            r2, f2, c2 = _coordinate_entries(llo, lhi, lowbits, low)
        else:
            r2, f2, c2 = r1[:0], f1[:0], c1[:0]
        _, cellkey = np.unique(np.concatenate([c1, c2]), axis=0, return_inverse=True)
        cellkey = cellkey.ravel()
        is_low = np.concatenate([np.zeros(r1.size, bool), np.ones(r2.size, bool)])
        order = np.lexsort((is_low, cellkey))
        cellkey, is_low = cellkey[order], is_low[order]
        rows = np.concatenate([r1, r2])[order].astype(index)
        first = np.concatenate([f1, f2])[order]
        del r1, r2, f1, f2, c1, c2, order
        del lo, hi, all7
        if low.size:
            del llo, lhi, lowbits
    new_cell = np.empty(cellkey.size, dtype=bool)
    new_cell[0] = True
    np.not_equal(cellkey[1:], cellkey[:-1], out=new_cell[1:])
    del cellkey
    starts = np.flatnonzero(new_cell).astype(index)
    del new_cell
    ends = np.append(starts[1:], index(rows.size))
    counts = np.repeat(ends, ends - starts)
    del starts, ends
    counts -= np.arange(1, rows.size + 1, dtype=index)
    counts[is_low] = 0                              # lower-level entries start no pair
    face = act.astype(index)[rows]
    del is_low
    cum = np.cumsum(counts, dtype=np.int64)
    total = int(cum[-1])
    if total >= JIT_MIN_SIZE:
        # the compiled loops read each face's box and masked ids by face row
        # (faces of one cell are mostly neighbours in memory): no gathers
        ebox = None
    else:
        # the entries' boxes in entry order (one array per bound): the pairs
        # of a cell read nearby memory
        ebox = [np.take(col, rows) for col in box]
        if faces.masked:
            ebox += [np.take(faces.masked_rows[:, k], face) for k in range(3)]
    del rows
    for s in range(0, total, _PAIR_CHUNK):
        yield partial(_pair_task, faces, (cum, counts, first, face, ebox),
                      s, min(s + _PAIR_CHUNK, total))


def _pair_task(faces, level, s, e):
    """Generate candidate pairs ``s .. e - 1`` of a level, filter, test them.

    ``level`` from the compiled grid (:func:`_level_grid`, three arrays):
    ``s .. e - 1`` are entries, every pair they start is examined.
    """
    if len(level) == 3:
        counts, first, face = level
        out = np.empty(int(counts[s:e].sum(dtype=np.int64)), dtype=np.int64)
        found = _entry_pair_loops(counts, first, face, faces.box32, faces.masked_rows, s, e,
                                  faces.F, faces.V, faces.plane, faces.tol, faces.E, out)
        return out[:found]
    cum, counts, first, face, ebox = level
    if ebox is None:
        out = np.empty(e - s, dtype=np.int64)
        found = _pair_loops(cum, counts, first, face, faces.box32, faces.masked_rows, s, e,
                            faces.F, faces.V, faces.plane, faces.tol, faces.E, out)
        return out[:found]
    p0 = int(np.searchsorted(cum, s, side="right"))
    p1 = int(np.searchsorted(cum, e - 1, side="right")) + 1
    index = np.int32 if first.size < 2 ** 31 else np.int64   # entry numbers
    b = cum[p0:p1] - counts[p0:p1]                  # first pair index of each entry
    a = np.maximum(b, s)
    n = np.minimum(cum[p0:p1], e) - a
    entries = np.arange(p0, p1, dtype=index)
    e1 = np.repeat(entries, n)
    e2 = np.repeat((a - b - (np.cumsum(n) - n) + 1).astype(index) + entries, n)
    e2 += np.arange(e2.size, dtype=index)
    # keep a pair only in the cell holding the low corner of the boxes'
    # intersection: there, on every axis, one of the two entries is its box's
    # lowest cell
    keep = np.flatnonzero((np.take(first, e1) | np.take(first, e2)) == 7)
    e1 = np.take(e1, keep)
    e2 = np.take(e2, keep)
    overlap = np.take(ebox[0], e1) <= np.take(ebox[3], e2)
    overlap &= np.take(ebox[0], e2) <= np.take(ebox[3], e1)
    for k in (1, 2):
        lo, hi = ebox[k], ebox[k + 3]
        overlap &= np.take(lo, e1) <= np.take(hi, e2)
        overlap &= np.take(lo, e2) <= np.take(hi, e1)
    keep = np.flatnonzero(overlap)
    e1 = np.take(e1, keep)
    e2 = np.take(e2, keep)
    del keep, overlap
    if len(ebox) > 6:
        # faces sharing a vertex whose fan is separated cannot intersect
        B = [np.take(col, e2) for col in ebox[6:]]
        skip = np.zeros(e1.size, dtype=bool)
        for col in ebox[6:]:
            x = np.take(col, e1)
            skip |= (x == B[0]) | (x == B[1]) | (x == B[2])
        e1 = e1[~skip]
        e2 = e2[~skip]
        del B, skip
    fa = np.take(face, e1).astype(np.int64)
    fb = np.take(face, e2).astype(np.int64)
    del e1, e2
    i = np.minimum(fa, fb)
    j = np.maximum(fa, fb)
    hit = np.empty(i.size, dtype=bool)
    for s in range(0, i.size, _NARROW_CHUNK):      # cache-sized narrow-phase batches
        hit[s:s + _NARROW_CHUNK] = _intersecting(faces, i[s:s + _NARROW_CHUNK],
                                                 j[s:s + _NARROW_CHUNK])
    return i[hit] * faces.F.shape[0] + j[hit]


# ---------------------------------------------------------------------------
# broad phase by parts (many small parts: mapped texture elements)


def _part_sweep(faces: _FaceData, parts: np.ndarray, *, mapper=map, side=None, within=None):
    """The intersecting pairs as keys ``i * m + j``, found by sweeping parts.

    Every pair of active faces whose boxes overlap is examined once, as on the
    grid (:func:`_pair_tasks`), with the same filters and narrow phase: pairs
    within a part by a sweep over the low x of their boxes, pairs of two
    parts whose boxes (the union of their faces' boxes) overlap by a sweep
    over the faces of each that overlap the other's box.  A part of more than
    ``_PART_MAX_FACES`` faces is cut into runs (:func:`_runs_of_large_parts`)
    swept as parts of their own, with the pairs of two runs of one part swept
    where that part's own pairs are wanted.  The parts are swept in chunks
    (``mapper``: the thread pool); the keys come back sorted.

    With ``side`` (per face, one value per part) only pairs of parts on
    different sides are swept, and within-part pairs only in the parts whose
    faces are ``within`` (per face; default none).
    """
    act = faces.active
    part = np.asarray(parts, dtype=np.int64)[act]
    if act.size == 0:
        return np.zeros(0, dtype=np.int64)
    _, first, part, count = np.unique(part, return_index=True, return_inverse=True,
                                      return_counts=True)
    part = part.ravel()
    porigin = np.arange(count.size, dtype=np.int64)
    if count.max() > _PART_MAX_FACES:           # large parts: swept as runs
        part, first, count, porigin = _runs_of_large_parts(faces.box32, act, part, count)
    if side is None:                            # every pair of parts, and within each
        pside = porigin
        pwithin = np.ones(count.size, dtype=bool)
    else:
        pside = np.asarray(side, dtype=np.int64)[act[first]]
        pwithin = (np.zeros(count.size, dtype=bool) if within is None
                   else np.asarray(within, dtype=bool)[act[first]])
    box = faces.box32
    pstart = np.concatenate([[0], np.cumsum(count)]).astype(np.int64)
    n_parts = count.size
    # the faces by part, then low x (ties in face order), and the parts'
    # boxes: each part sorted on its own, the parts in pieces on the pool
    grouped = _grouped_by_part(part, pstart)
    order = np.empty(act.size, dtype=np.int64)
    pbox = np.empty((n_parts, 6), dtype=np.float32)
    bounds = np.searchsorted(pstart, _pieces(act.size, _workers())).astype(np.int64)
    bounds[-1] = n_parts
    _each(mapper, bounds,
          lambda k, s, e: _part_order(grouped, act, box, pstart, s, e, order, pbox))
    del grouped
    porder = np.argsort(pbox[:, 0], kind="stable").astype(np.int64)
    cuts = np.linspace(0, n_parts, min(n_parts, 16) + 1).astype(np.int64)
    keys = list(mapper(lambda k: _part_loops(order, pstart, pbox, porder, pside, pwithin,
                                             porigin, int(cuts[k]), int(cuts[k + 1]), box,
                                             faces.masked_rows, faces.F, faces.V, faces.plane,
                                             faces.tol, faces.E), range(cuts.size - 1)))
    return np.sort(np.concatenate(keys)) if keys else np.zeros(0, dtype=np.int64)


def _runs_of_large_parts(box, act, part, count):
    """Parts above ``_PART_MAX_FACES`` faces cut into runs of ``_PART_RUN`` faces.

    ``part`` (a rank per active face) and ``count`` are those of
    :func:`_part_sweep`; a large part's faces are ordered by the Morton code
    of their box centres (ties in face order), so that a run is a compact
    patch whose box overlaps few others.  Returns the new ``part`` (a rank
    per active face: the runs of a part follow each other, in its place
    among the parts), ``first`` (an active face of each), ``count`` and
    ``porigin`` (the part each came from).
    """
    rows = np.flatnonzero(count[part] > _PART_MAX_FACES)
    f = act[rows]
    centre = 0.5 * (box[f, :3].astype(np.float64) + box[f, 3:])
    # normalised coordinates lie within (-1, 1): 21 bits per axis
    q = np.clip(np.floor((centre + 1.0) * 2.0 ** 20), 0, 2 ** 21 - 1).astype(np.uint64)
    code = _spread_bits(q[:, 0]) | (_spread_bits(q[:, 1]) << np.uint64(1)) \
        | (_spread_bits(q[:, 2]) << np.uint64(2))
    rows = rows[np.lexsort((code, part[rows]))]  # by part, then code (stable: face order)
    of = part[rows]
    rank = np.arange(rows.size) - np.searchsorted(of, of)
    runs = -(-int(count.max()) // _PART_RUN)
    key = part * runs
    key[rows] += rank // _PART_RUN
    _, first, sub, count = np.unique(key, return_index=True, return_inverse=True,
                                     return_counts=True)
    return sub.ravel(), first, count, part[first]


def _spread_bits(x: np.ndarray) -> np.ndarray:
    """The 21 low bits of ``x`` (uint64) moved to bits 0, 3, 6, ... (Morton code)."""
    x = x & np.uint64(0x1FFFFF)
    for shift, mask in ((32, 0x1F00000000FFFF), (16, 0x1F0000FF0000FF),
                        (8, 0x100F00F00F00F00F), (4, 0x10C30C30C30C30C3),
                        (2, 0x1249249249249249)):
        x = (x | (x << np.uint64(shift))) & np.uint64(mask)
    return x


@compiled
def _grouped_by_part(part, pstart):
    """The rows ``0 .. len(part) - 1`` grouped by ``part`` (a rank: part ``p``'s
    rows at ``pstart[p]:pstart[p + 1]``), in row order within a part."""
    at = pstart[:-1].copy()
    out = np.empty(part.shape[0], np.int64)
    for r in range(part.shape[0]):
        p = part[r]
        out[at[p]] = r
        at[p] += 1
    return out


@compiled
def _part_order(grouped, act, box, pstart, p0, p1, order, pbox):
    """For parts ``p0 .. p1 - 1``: their faces by the low x of their boxes (a
    stable sort: ties in face order, as ``np.lexsort``) into ``order``, and the
    union of their boxes into ``pbox``."""
    for p in range(p0, p1):
        s, e = pstart[p], pstart[p + 1]
        x = np.empty(e - s, np.float32)
        for k in range(s, e):
            x[k - s] = box[act[grouped[k]], 0]
        o = np.argsort(x, kind="mergesort")
        for k in range(e - s):
            order[s + k] = act[grouped[s + o[k]]]
        f = order[s]
        for a in range(6):
            pbox[p, a] = box[f, a]
        for k in range(s + 1, e):
            f = order[k]
            for a in range(3):
                pbox[p, a] = min(pbox[p, a], box[f, a])
                pbox[p, 3 + a] = max(pbox[p, 3 + a], box[f, 3 + a])


@helper
def _pushed(out, found, key):
    if found == out.shape[0]:
        grown = np.empty(2 * out.shape[0], dtype=np.int64)
        grown[:found] = out[:found]
        out = grown
    out[found] = key
    return out


@compiled
def _part_loops(order, pstart, pbox, porder, pside, pwithin, porigin, c0, c1, box, mrows, F, V,
                plane, tol, E):
    """Sweeps of :func:`_part_sweep`: ``order`` holds the active faces by part,
    then low x; part ``p`` is ``order[pstart[p]:pstart[p + 1]]``; ``porder``
    lists the parts by the low x of their boxes ``pbox``.  Sweeps parts
    ``c0 .. c1 - 1`` (those with ``pwithin``) and the pairs of parts whose
    first (in ``porder``) is ``porder[c0 .. c1 - 1]`` (those of different
    ``pside``, and runs of one ``porigin`` part with ``pwithin``).  Returns
    the keys."""
    # the box and fan tests are written out in the loops: a call passing
    # arrays costs reference counting, which would cost more than the tests
    m = F.shape[0]
    masked = mrows.shape[0] > 0
    out = np.empty(1024, dtype=np.int64)
    found = 0
    n_parts = pstart.shape[0] - 1
    for p in range(c0, c1):                      # within a part
        if not pwithin[p]:
            continue
        s, e = pstart[p], pstart[p + 1]
        for x in range(s, e):
            fa = order[x]
            hx = box[fa, 3]
            for y in range(x + 1, e):
                fb = order[y]
                if box[fb, 0] > hx:
                    break
                if (box[fa, 0] > box[fb, 3] or box[fa, 1] > box[fb, 4] or box[fb, 1] > box[fa, 4]
                        or box[fa, 2] > box[fb, 5] or box[fb, 2] > box[fa, 5]):
                    continue
                if masked and (mrows[fa, 0] == mrows[fb, 0] or mrows[fa, 0] == mrows[fb, 1]
                               or mrows[fa, 0] == mrows[fb, 2] or mrows[fa, 1] == mrows[fb, 0]
                               or mrows[fa, 1] == mrows[fb, 1] or mrows[fa, 1] == mrows[fb, 2]
                               or mrows[fa, 2] == mrows[fb, 0] or mrows[fa, 2] == mrows[fb, 1]
                               or mrows[fa, 2] == mrows[fb, 2]):
                    continue
                if _pair_hits(min(fa, fb), max(fa, fb), F, V, plane, tol, E):
                    out = _pushed(out, found, min(fa, fb) * m + max(fa, fb))
                    found += 1
    largest = 0
    for p in range(n_parts):
        largest = max(largest, pstart[p + 1] - pstart[p])
    la = np.empty(largest, dtype=np.int64)
    lb = np.empty(largest, dtype=np.int64)
    for ia in range(c0, c1):                     # pairs of parts whose boxes meet
        p = porder[ia]
        for ib in range(ia + 1, n_parts):
            q = porder[ib]
            if pbox[q, 0] > pbox[p, 3]:
                break
            if pside[p] == pside[q] and not (pwithin[p] and porigin[p] == porigin[q]):
                continue
            if (pbox[p, 1] > pbox[q, 4] or pbox[q, 1] > pbox[p, 4]
                    or pbox[p, 2] > pbox[q, 5] or pbox[q, 2] > pbox[p, 5]):
                continue
            na = 0
            for x in range(pstart[p], pstart[p + 1]):
                f = order[x]
                if not (box[f, 0] > pbox[q, 3] or pbox[q, 0] > box[f, 3] or box[f, 1] > pbox[q, 4]
                        or pbox[q, 1] > box[f, 4] or box[f, 2] > pbox[q, 5]
                        or pbox[q, 2] > box[f, 5]):
                    la[na] = f
                    na += 1
            nb = 0
            for x in range(pstart[q], pstart[q + 1]):
                f = order[x]
                if not (box[f, 0] > pbox[p, 3] or pbox[p, 0] > box[f, 3] or box[f, 1] > pbox[p, 4]
                        or pbox[p, 1] > box[f, 4] or box[f, 2] > pbox[p, 5]
                        or pbox[p, 2] > box[f, 5]):
                    lb[nb] = f
                    nb += 1
            start = 0                            # both lists by low x
            for x in range(na):
                fa = la[x]
                while start < nb and box[lb[start], 3] < box[fa, 0]:
                    start += 1                   # cannot meet fa nor any later face
                for y in range(start, nb):
                    fb = lb[y]
                    if box[fb, 0] > box[fa, 3]:
                        break
                    if (box[fb, 3] < box[fa, 0] or box[fa, 1] > box[fb, 4]
                            or box[fb, 1] > box[fa, 4] or box[fa, 2] > box[fb, 5]
                            or box[fb, 2] > box[fa, 5]):
                        continue
                    if masked and (mrows[fa, 0] == mrows[fb, 0] or mrows[fa, 0] == mrows[fb, 1]
                                   or mrows[fa, 0] == mrows[fb, 2] or mrows[fa, 1] == mrows[fb, 0]
                                   or mrows[fa, 1] == mrows[fb, 1] or mrows[fa, 1] == mrows[fb, 2]
                                   or mrows[fa, 2] == mrows[fb, 0] or mrows[fa, 2] == mrows[fb, 1]
                                   or mrows[fa, 2] == mrows[fb, 2]):
                        continue
                    if _pair_hits(min(fa, fb), max(fa, fb), F, V, plane, tol, E):
                        out = _pushed(out, found, min(fa, fb) * m + max(fa, fb))
                        found += 1
    return out[:found].copy()


# ---------------------------------------------------------------------------
# narrow phase


def _intersecting(faces: _FaceData, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Return a boolean mask: which face pairs ``(i[k], j[k])`` intersect."""
    out = np.zeros(i.size, dtype=bool)
    if i.size == 0:
        return out
    FA = np.take(faces.F, i, axis=0)
    FB = np.take(faces.F, j, axis=0)
    eq = FA[:, :, None] == FB[:, None, :]
    shA = eq[:, :, 0] | eq[:, :, 1] | eq[:, :, 2]   # corner of A shared with B
    shB = eq[:, 0, :] | eq[:, 1, :] | eq[:, 2, :]
    del eq
    nshared = shA[:, 0].astype(np.int8) + shA[:, 1] + shA[:, 2]
    PA = np.take(faces.V, FA.ravel(), axis=0).reshape(-1, 3, 3)
    PB = np.take(faces.V, FB.ravel(), axis=0).reshape(-1, 3, 3)
    plA = np.take(faces.plane, i, axis=0)
    plB = np.take(faces.plane, j, axis=0)
    tol = np.maximum(np.take(faces.tol, i), np.take(faces.tol, j))
    t = tol[:, None]
    # signed distances of the corners of each triangle to the other's plane
    dA = np.einsum("nkc,nc->nk", PA, plB[:, :3]) - plB[:, 3:4]
    dB = np.einsum("nkc,nc->nk", PB, plA[:, :3]) - plA[:, 3:4]

    def strictly_one_side(d, sh):
        # every corner not shared with the other face is strictly on one side
        above = (d > t) | sh
        below = (d < -t) | sh
        return ((above[:, 0] & above[:, 1] & above[:, 2])
                | (below[:, 0] & below[:, 1] & below[:, 2]))

    rejA = strictly_one_side(dA, shA)
    rejB = strictly_one_side(dB, shB)
    # a shared edge needs one face in the other's plane; otherwise one plane
    # separating the other face's free corners is enough
    alive = np.where(nshared == 2, ~(rejA & rejB), ~(rejA | rejB)) & (nshared < 3)
    if not alive.any():
        return out
    near = np.abs(dA) <= t
    coplanar = near[:, 0] & near[:, 1] & near[:, 2]      # A lies in the plane of B
    near = np.abs(dB) <= t
    coplanar |= near[:, 0] & near[:, 1] & near[:, 2]
    k = np.flatnonzero(alive & (nshared == 2))
    if k.size:
        out[k] = _folded(faces, i[k], j[k], shA[k], shB[k], dA[k], dB[k], tol[k])
    k = np.flatnonzero(alive & (nshared == 1) & coplanar)
    if k.size:
        out[k] = _wedges_overlap(faces, i[k], j[k], shA[k], shB[k], tol[k])
    k = np.flatnonzero(alive & (nshared == 0) & coplanar)
    if k.size:
        out[k] = _coplanar_overlap(faces, i[k], j[k], PA[k], PB[k], tol[k])
    k = np.flatnonzero(alive & (nshared < 2) & ~coplanar)
    if k.size:
        EA = np.take(faces.E, i[k], axis=0).reshape(-1, 3, 4)
        EB = np.take(faces.E, j[k], axis=0).reshape(-1, 3, 4)
        out[k] = (_endpoints_inside(PA[k], dA[k], shA[k], EB, tol[k])
                  | _endpoints_inside(PB[k], dB[k], shB[k], EA, tol[k]))
    return out


def _dot(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Dot product over the last axis of length 3, written out."""
    return a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2]


def _edge_rows(faces: _FaceData, f: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Edge planes ``faces.E`` of edge ``k`` of faces ``f``, ``(n, 4)``."""
    return np.take(faces.E.reshape(-1, 4), 3 * f + k, axis=0)


def _corner_points(faces: _FaceData, f: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Position of corner ``k`` of faces ``f``, ``(n, 3)``."""
    return np.take(faces.V, np.take(faces.F.reshape(-1), 3 * f + k), axis=0)


def _edge_distance(plane: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Signed distance of ``x``'s projection to an edge line (positive inside)."""
    return _dot(plane[:, :3], x) - plane[:, 3]


def _folded(faces, i, j, shA, shB, dA, dB, tol) -> np.ndarray:
    """Faces sharing an edge: one lies in the other's plane, folded onto it.

    With ``a`` and ``b`` the corners off the shared edge: folded when ``b``
    is within the tolerance of A's plane and strictly on ``a``'s side of the
    shared edge, or the converse.
    """
    r = np.arange(tol.size)
    ka = np.argmin(shA, axis=1)                  # the corner off the shared edge
    kb = np.argmin(shB, axis=1)
    # edge (k + 1) % 3 is the one opposite corner k: the shared edge
    side_b = _edge_distance(_edge_rows(faces, i, (ka + 1) % 3), _corner_points(faces, j, kb))
    side_a = _edge_distance(_edge_rows(faces, j, (kb + 1) % 3), _corner_points(faces, i, ka))
    return (((np.abs(dB[r, kb]) <= tol) & (side_b > tol))
            | ((np.abs(dA[r, ka]) <= tol) & (side_a > tol)))


def _wedges_overlap(faces, i, j, shA, shB, tol) -> np.ndarray:
    """Coplanar faces sharing one corner: do their wedges there overlap?

    Two convex wedges with a common apex share more than the apex exactly
    when one of the four boundary rays lies in the other (closed) wedge; the
    ray to a corner lies in the wedge when the corner is on the inner side of
    both edges at the apex (within the tolerance).
    """
    ka = np.argmax(shA, axis=1)                  # the shared corner
    kb = np.argmax(shB, axis=1)
    ntol = -tol

    def rays_in_wedge(f, k, g, kg):
        # wedge of face f at its corner k; rays to corners kg+1, kg+2 of face g
        e1 = _edge_rows(faces, f, k)             # the two edges at corner k
        e2 = _edge_rows(faces, f, (k + 2) % 3)
        hit = np.zeros(tol.size, dtype=bool)
        for step in (1, 2):
            x = _corner_points(faces, g, (kg + step) % 3)
            hit |= (_edge_distance(e1, x) >= ntol) & (_edge_distance(e2, x) >= ntol)
        return hit

    return rays_in_wedge(i, ka, j, kb) | rays_in_wedge(j, kb, i, ka)


def _coplanar_overlap(faces, i, j, PA, PB, tol) -> np.ndarray:
    """Coplanar faces without shared corner: separating axis test in the plane.

    Two convex polygons in a plane are disjoint exactly when the line of one
    of their edges has the other polygon strictly outside.
    """
    ntol = -tol
    out = np.ones(tol.size, dtype=bool)
    rows = np.arange(tol.size)
    for f, Y in ((i, PB), (j, PA)):
        # the other triangle's corners and these edge planes, one contiguous
        # array per coordinate; pairs already separated drop out
        E = np.take(faces.E, f[rows], axis=0).T.copy()
        Yc = Y[rows].reshape(-1, 9).T.copy()
        t = ntol[rows]
        separated = np.zeros(rows.size, dtype=bool)
        for k in range(3):
            wx, wy, wz, w0 = E[4 * k:4 * k + 4]
            out_k = np.ones(rows.size, dtype=bool)
            for c in range(3):
                out_k &= wx * Yc[3 * c] + wy * Yc[3 * c + 1] + wz * Yc[3 * c + 2] - w0 < t
            separated |= out_k
        out[rows[separated]] = False
        rows = rows[~separated]
        if rows.size == 0:
            break
    return out


def _endpoints_inside(PX, dX, shX, EY, tol):
    """Is an endpoint of ``X`` ∩ plane(Y) inside triangle ``Y``?

    ``X`` and ``Y`` are not coplanar.  The candidate endpoints are the corners
    of ``X`` in the plane of ``Y`` and the crossings of ``X``'s edges with it;
    a corner shared with ``Y`` (and any point within the tolerance of it) is
    not a candidate, so faces sharing a corner must meet elsewhere.
    """
    t = tol[:, None]
    d1 = np.roll(dX, -1, axis=1)
    on_plane = (np.abs(dX) <= t) & ~shX
    crossing = ((dX > t) & (d1 < -t)) | ((dX < -t) & (d1 > t))
    rv, kv = np.nonzero(on_plane)
    rc, kc = np.nonzero(crossing)
    s = dX[rc, kc] / (dX[rc, kc] - d1[rc, kc])
    start = PX[rc, kc]
    pts = np.concatenate([PX[rv, kv], start + (PX[rc, (kc + 1) % 3] - start) * s[:, None]])
    rows = np.concatenate([rv, rc])
    tr = tol[rows]
    keep = np.ones(rows.size, dtype=bool)
    shared = shX.any(axis=1)[rows]
    if shared.any():
        p = PX[rows[shared], np.argmax(shX[rows[shared]], axis=1)]
        diff = pts[shared] - p
        keep[shared] = _dot(diff, diff) > tr[shared] ** 2
    E = EY[rows]
    for k in range(3):
        keep &= _dot(E[:, k, :3], pts) - E[:, k, 3] >= -tr
    out = np.zeros(PX.shape[0], dtype=bool)
    out[rows[keep]] = True
    return out


# ---------------------------------------------------------------------------
# compiled: the pair task and the narrow phase as loops (large inputs)


@compiled
def _pair_loops(cum, counts, first, face, box, mrows, s, e, F, V, plane, tol, E, out):
    """:func:`_pair_task` as loops: the same pairs, filters and narrow phase
    (:func:`_intersecting`, case by case), the hits written to ``out`` as keys
    in the same order; returns their number.  ``box`` is
    :attr:`_FaceData.box32` and ``mrows`` :attr:`_FaceData.masked_rows` (no
    rows: no mask), both read by face."""
    m = F.shape[0]
    masked = mrows.shape[0] > 0
    found = 0
    p = np.searchsorted(cum, s, side="right")
    while p < cum.shape[0]:
        base = cum[p] - counts[p]                # pair number of (p, p + 1)
        if base >= e:
            break
        g0 = max(base, s)
        g1 = min(cum[p], e)
        fp = first[p]
        fa = face[p]
        a0, a1, a2 = box[fa, 0], box[fa, 1], box[fa, 2]
        a3, a4, a5 = box[fa, 3], box[fa, 4], box[fa, 5]
        for g in range(g0, g1):
            q = p + 1 + (g - base)
            if (fp | first[q]) != 7:
                continue
            fb = face[q]
            if (a0 > box[fb, 3] or box[fb, 0] > a3 or a1 > box[fb, 4] or box[fb, 1] > a4
                    or a2 > box[fb, 5] or box[fb, 2] > a5):
                continue
            if masked:
                x0, x1, x2 = mrows[fa, 0], mrows[fa, 1], mrows[fa, 2]
                y0, y1, y2 = mrows[fb, 0], mrows[fb, 1], mrows[fb, 2]
                if (x0 == y0 or x0 == y1 or x0 == y2 or x1 == y0 or x1 == y1 or x1 == y2
                        or x2 == y0 or x2 == y1 or x2 == y2):
                    continue
            i = min(fa, fb)
            j = max(fa, fb)
            if _pair_hits(i, j, F, V, plane, tol, E):
                out[found] = i * m + j
                found += 1
        p += 1
    return found


@compiled
def _face_loops(V, F, plane, tol, E, box32, bad, s, e):
    """:meth:`_FaceData._fill` as a loop over faces ``s .. e - 1`` (the same
    expressions in the same order: bit for bit the same arrays)."""
    for f in range(s, e):
        i0, i1, i2 = F[f, 0], F[f, 1], F[f, 2]
        x0, y0, z0 = V[i0, 0], V[i0, 1], V[i0, 2]
        x1, y1, z1 = V[i1, 0], V[i1, 1], V[i1, 2]
        x2, y2, z2 = V[i2, 0], V[i2, 1], V[i2, 2]
        e0x, e0y, e0z = x1 - x0, y1 - y0, z1 - z0
        e1x, e1y, e1z = x2 - x1, y2 - y1, z2 - z1
        e2x, e2y, e2z = x0 - x2, y0 - y2, z0 - z2
        nx = e0z * e2y - e0y * e2z
        ny = e0x * e2z - e0z * e2x
        nz = e0y * e2x - e0x * e2y
        double_area = np.sqrt(nx * nx + ny * ny + nz * nz)
        l0 = e0x * e0x + e0y * e0y + e0z * e0z
        l1 = e1x * e1x + e1y * e1y + e1z * e1z
        l2 = e2x * e2x + e2y * e2y + e2z * e2z
        longest2 = max(max(l0, l1), l2)
        degenerate = (not (double_area > _DEGENERATE_REL_TOL * longest2)
                      or i0 == i1 or i1 == i2 or i2 == i0)
        bad[f] = degenerate
        inv = 0.0 if degenerate else 1.0 / double_area
        ux, uy, uz = nx * inv, ny * inv, nz * inv
        plane[f, 0] = ux
        plane[f, 1] = uy
        plane[f, 2] = uz
        plane[f, 3] = ux * x0 + uy * y0 + uz * z0
        t = REL_TOL * np.sqrt(longest2) + ABS_TOL
        tol[f] = t
        for k in range(3):
            if k == 0:
                ex, ey, ez, lk, px, py, pz = e0x, e0y, e0z, l0, x0, y0, z0
            elif k == 1:
                ex, ey, ez, lk, px, py, pz = e1x, e1y, e1z, l1, x1, y1, z1
            else:
                ex, ey, ez, lk, px, py, pz = e2x, e2y, e2z, l2, x2, y2, z2
            inv_len = 0.0 if degenerate else 1.0 / np.sqrt(lk)
            wx = (uy * ez - uz * ey) * inv_len
            wy = (uz * ex - ux * ez) * inv_len
            wz = (ux * ey - uy * ex) * inv_len
            E[f, 4 * k] = wx
            E[f, 4 * k + 1] = wy
            E[f, 4 * k + 2] = wz
            E[f, 4 * k + 3] = wx * px + wy * py + wz * pz
        pad = 2.0 * t + _BOX32_PAD
        box32[f, 0] = np.float32(min(min(x0, x1), x2) - pad)
        box32[f, 1] = np.float32(min(min(y0, y1), y2) - pad)
        box32[f, 2] = np.float32(min(min(z0, z1), z2) - pad)
        box32[f, 3] = np.float32(max(max(x0, x1), x2) + pad)
        box32[f, 4] = np.float32(max(max(y0, y1), y2) + pad)
        box32[f, 5] = np.float32(max(max(z0, z1), z2) + pad)


@compiled
def _entry_pair_loops(counts, first, face, box, mrows, s, e, F, V, plane, tol, E, out):
    """:func:`_pair_loops` over the entries ``s .. e - 1`` of a compiled grid
    (:func:`_level_grid`): entry ``p`` is paired with the ``counts[p]``
    entries after it.  Returns the number of hits written to ``out``."""
    m = F.shape[0]
    masked = mrows.shape[0] > 0
    found = 0
    for p in range(s, e):
        c = counts[p]
        if c == 0:
            continue
        fp = first[p]
        fa = face[p]
        a0, a1, a2 = box[fa, 0], box[fa, 1], box[fa, 2]
        a3, a4, a5 = box[fa, 3], box[fa, 4], box[fa, 5]
        for q in range(p + 1, p + 1 + c):
            if (fp | first[q]) != 7:
                continue
            fb = face[q]
            if (a0 > box[fb, 3] or box[fb, 0] > a3 or a1 > box[fb, 4] or box[fb, 1] > a4
                    or a2 > box[fb, 5] or box[fb, 2] > a5):
                continue
            if masked:
                x0, x1, x2 = mrows[fa, 0], mrows[fa, 1], mrows[fa, 2]
                y0, y1, y2 = mrows[fb, 0], mrows[fb, 1], mrows[fb, 2]
                if (x0 == y0 or x0 == y1 or x0 == y2 or x1 == y0 or x1 == y1 or x1 == y2
                        or x2 == y0 or x2 == y1 or x2 == y2):
                    continue
            i = min(fa, fb)
            j = max(fa, fb)
            if _pair_hits(i, j, F, V, plane, tol, E):
                out[found] = i * m + j
                found += 1
    return found


@helper
def _cell_of(x, cell):
    """The grid cell of coordinate ``x`` (a float32 box bound), as :func:`_cell_bounds`."""
    return np.int64(np.floor(np.float64(x) / cell))


@helper
def _cell_span(box32, f, a, cell, cmin, cmax, clip):
    """Cells ``lo .. hi`` covered on axis ``a`` by face ``f``'s box and the
    axis's corner bit (``1 << a`` when ``lo`` is the box's true lowest cell,
    else 0); with ``clip`` the range is clipped to ``cmin[a] .. cmax[a]``
    (empty: ``lo > hi``).  Scalars: no array per face (two small arrays per
    face were most of the grid's time)."""
    lo = _cell_of(box32[f, a], cell)
    hi = _cell_of(box32[f, 3 + a], cell)
    bit = 1 << a
    if clip:
        if lo < cmin[a]:
            bit = 0
            lo = cmin[a]
        hi = min(hi, cmax[a])
    return lo, hi, bit


@helper
def _emit_entries(box32, act, rows, cell, cmin, cmax, size, clip, flag, shift, occ, keys, grow):
    """Packed keys ``(cell, flag, row, corner bits)`` of the entries of the
    boxes of ``rows`` (face by face, cells in x, y, z order), written to
    ``keys`` when it has room or (``grow``) appended to it, grown as needed
    (else only counted); with ``clip``, clipped to the grid; kept only in
    cells the bit array ``occ`` marks when it has words.  Returns the number
    of entries and ``keys`` (grown or not)."""
    w = 0
    write = grow or keys.shape[0] > 0
    use_occ = occ.shape[0] > 0
    for r in range(rows.shape[0]):
        f = act[rows[r]]
        lx, hx, bx = _cell_span(box32, f, 0, cell, cmin, cmax, clip)
        ly, hy, by = _cell_span(box32, f, 1, cell, cmin, cmax, clip)
        lz, hz, bz = _cell_span(box32, f, 2, cell, cmin, cmax, clip)
        bits = bx | by | bz
        for x in range(lx, hx + 1):
            for y in range(ly, hy + 1):
                for z in range(lz, hz + 1):
                    c = ((x - cmin[0]) * size[1] + (y - cmin[1])) * size[2] + (z - cmin[2])
                    if use_occ and not occ[c >> 6] & (np.uint64(1) << np.uint64(c & 63)):
                        continue
                    if write:
                        corner = ((1 if x == lx else 0) | (2 if y == ly else 0)
                                  | (4 if z == lz else 0))
                        key = (((c * 2 + flag) << shift) | (np.int64(rows[r]) << 3)
                               | (bits & corner))
                        if grow:
                            keys = _pushed(keys, w, key)
                        else:
                            keys[w] = key
                    w += 1
    return w, keys


def _level_grid(box32, act, cur, low, cell, row_bits, key_bits, chunk, occ_cells, *,
                mapper=map, split=1):
    """One level's grid of :func:`_level_tasks` in loops.

    The same entries as the numpy path (packed keys sorted by cell, the
    current level's entries first; smaller faces only in cells holding a
    current-level face; within a cell in row order, where the numpy path
    keeps the order of its cell offsets: the same pairs), returned as
    ``(ok, first, face, counts, cuts)``: per entry its corner bits, its face
    (int32) and how many entries after it it is paired with (0 for a smaller
    face's entry); ``cuts`` splits the entries into tasks of about ``chunk``
    pairs.  ``ok`` is false (and the arrays empty) when the cell keys do not
    fit ``key_bits`` bits (the caller takes the numpy path).  The cell ranges
    are recomputed from the boxes where needed, never stored.

    The loops over faces and entries (extent, entries, radix passes, rows)
    run in up to ``split`` contiguous pieces of at least ``_GRID_PIECE``
    items on ``mapper`` (the pool); each piece fills its own range of the
    output (a radix pass: counts per piece, then each piece places its keys
    after those of the pieces before it), so the arrays are the same bit for
    bit whatever ``split`` is.  The occupied-cell bits, the merge with the
    smaller faces and the task cuts stay in one loop each.
    """
    shift = row_bits + 3
    ext = np.empty((split, 6), np.int64)
    bounds = _pieces(cur.size, split)
    _each(mapper, bounds, lambda k, s, e: _grid_extent(box32, act, cur[s:e], cell, ext[k]))
    k = bounds.size - 1
    cmin = ext[:k, :3].min(axis=0)
    cmax = ext[:k, 3:].max(axis=0)
    size = cmax - cmin + 1
    if not (float(size[0]) * size[1] * size[2] * 2 < 2.0 ** (key_bits - shift)):
        return False, np.empty(0, np.uint8), np.empty(0, np.int32), np.empty(0, np.int32), \
            np.empty(0, np.int64)
    no_occ = np.empty(0, np.uint64)
    keys = _grid_entries(box32, act, cur, cell, cmin, cmax, size, shift, mapper, split)
    cell_bits = (int(size[0]) * int(size[1]) * int(size[2]) * 2 - 1).bit_length()
    keys = _radix_pieces(keys, shift, cell_bits, mapper, split)
    if low.shape[0]:
        # smaller faces: clipped to the level's cells, kept in cells holding a
        # current-level entry (a bit per cell for at most ``occ_cells`` cells)
        ncells = size[0] * size[1] * size[2]
        occ = no_occ
        if ncells <= occ_cells:
            occ = np.zeros((ncells + 63) >> 6, np.uint64)
            _grid_occupied(keys, shift, occ)
        lkeys = _grid_low(box32, act, low, cell, cmin, cmax, size, shift, occ, mapper, split)
        if occ.shape[0] == 0 and lkeys.size:
            bounds = _pieces(lkeys.size, split)
            kept = np.zeros(bounds.size - 1, np.int64)

            def keep(k, s, e):
                kept[k] = _grid_in_cells(lkeys[s:e], keys, shift)

            _each(mapper, bounds, keep)
            lkeys = np.concatenate([lkeys[s:s + w] for s, w in zip(bounds[:-1], kept)])
        lkeys = _radix_pieces(lkeys, shift, cell_bits, mapper, split)
        keys = _grid_merged(keys, lkeys, shift)
        del lkeys
    total = keys.shape[0]
    first = np.empty(total, np.uint8)
    face = np.empty(total, np.int32)
    counts = np.zeros(total, np.int32)
    bounds = _pieces(total, split)
    for k in range(1, bounds.size - 1):              # pieces of whole cells
        bounds[k] = _grid_cell_start(keys, max(int(bounds[k]), int(bounds[k - 1])), shift)
    _each(mapper, bounds,
          lambda k, s, e: _grid_rows(keys, act, row_bits, shift, s, e, first, face, counts))
    return True, first, face, counts, _grid_cuts(counts, chunk)


def _pieces(n: int, split: int) -> np.ndarray:
    """Bounds of up to ``split`` near-equal pieces of ``range(n)``, each of at least
    ``_GRID_PIECE`` items (one piece below that)."""
    k = max(1, min(split, n // _GRID_PIECE))
    return (np.arange(k + 1, dtype=np.int64) * n) // k


def _each(mapper, bounds, fn):
    """``fn(k, s, e)`` for each piece ``k`` of ``bounds`` (on ``mapper``; one piece
    in this thread)."""
    if bounds.size == 2:
        fn(0, int(bounds[0]), int(bounds[1]))
        return
    for _ in mapper(lambda k: fn(k, int(bounds[k]), int(bounds[k + 1])), range(bounds.size - 1)):
        pass


def _grid_entries(box32, act, rows, cell, cmin, cmax, size, shift, mapper, split):
    """:func:`_grid_count` and :func:`_grid_write` of ``rows`` in pieces: counted,
    then written each to its own range (the keys in row order, as in one loop)."""
    bounds = _pieces(rows.size, split)
    count = np.zeros(bounds.size - 1, np.int64)

    def counted(k, s, e):
        count[k] = _grid_count(box32, act, rows[s:e], cell, cmin, cmax, size, shift)

    _each(mapper, bounds, counted)
    at = np.concatenate([[0], np.cumsum(count)])
    keys = np.empty(int(at[-1]), np.int64)

    def written(k, s, e):
        if count[k]:
            _grid_write(box32, act, rows[s:e], cell, cmin, cmax, size, shift,
                        keys[at[k]:at[k + 1]])

    _each(mapper, bounds, written)
    return keys


def _grid_low(box32, act, rows, cell, cmin, cmax, size, shift, occ, mapper, split):
    """:func:`_grid_low_entries` of ``rows`` in pieces, joined in row order."""
    bounds = _pieces(rows.size, split)
    got = [None] * (bounds.size - 1)

    def emitted(k, s, e):
        got[k] = _grid_low_entries(box32, act, rows[s:e], cell, cmin, cmax, size, shift, occ)

    _each(mapper, bounds, emitted)
    return got[0].copy() if len(got) == 1 else np.concatenate(got)


def _radix_pieces(keys, shift, bits, mapper, split):
    """:func:`_radix_by_high_bits` with each pass in pieces: digit counts per piece,
    then each piece places its keys after the same digits of the pieces before
    it (the same stable order).  ``keys`` is overwritten; returns the sorted keys."""
    bounds = _pieces(keys.size, split)
    if bounds.size == 2:
        return _sorted_by_high_bits_inplace(keys, shift, bits)
    dst = np.empty_like(keys)
    done = 0
    while done < bits:
        sh = shift + done
        count = np.zeros((bounds.size - 1, 2048), np.int64)
        _each(mapper, bounds, lambda k, s, e: _radix_count(keys, s, e, sh, count[k]))
        start = np.cumsum(count.sum(axis=0)) - count.sum(axis=0) + np.cumsum(count, axis=0) - count
        _each(mapper, bounds, lambda k, s, e: _radix_place(keys, dst, s, e, sh, start[k]))
        keys, dst = dst, keys
        done += 11
    return keys


@compiled
def _grid_extent(box32, act, rows, cell, out):
    """Lowest and highest cell (``out[:3]``, ``out[3:]``) covered by the boxes of ``rows``."""
    for a in range(3):
        out[a] = np.iinfo(np.int64).max
        out[3 + a] = np.iinfo(np.int64).min
    for r in range(rows.shape[0]):
        f = act[rows[r]]
        for a in range(3):
            out[a] = min(out[a], _cell_of(box32[f, a], cell))
            out[3 + a] = max(out[3 + a], _cell_of(box32[f, 3 + a], cell))


@compiled
def _grid_count(box32, act, rows, cell, cmin, cmax, size, shift):
    """The number of entries :func:`_emit_entries` gives the level's faces
    ``rows`` (a piece).  The options are constants in each call of it: the
    compiled loop is several times faster specialised for them."""
    return _emit_entries(box32, act, rows, cell, cmin, cmax, size, False, 0, shift,
                         np.empty(0, np.uint64), np.empty(0, np.int64), False)[0]


@compiled
def _grid_write(box32, act, rows, cell, cmin, cmax, size, shift, keys):
    """:func:`_grid_count`, writing the entries to ``keys``."""
    _emit_entries(box32, act, rows, cell, cmin, cmax, size, False, 0, shift,
                  np.empty(0, np.uint64), keys, False)


@compiled
def _grid_low_entries(box32, act, rows, cell, cmin, cmax, size, shift, occ):
    """The entries of the smaller faces ``rows`` (a piece), clipped to the
    grid and kept in the cells of ``occ`` (all without words), in one pass
    (most of these faces are scanned for no entry or one)."""
    keys = np.empty(max(16, rows.shape[0]), np.int64)
    w, keys = _emit_entries(box32, act, rows, cell, cmin, cmax, size, True, 1, shift, occ, keys,
                            True)
    return keys[:w]


@compiled
def _radix_count(src, s, e, sh, count):
    """Counts of the 11-bit digit at bit ``sh`` of ``src[s:e]``."""
    for k in range(s, e):
        count[(src[k] >> sh) & 2047] += 1


@compiled
def _radix_place(src, dst, s, e, sh, start):
    """Place ``src[s:e]`` in ``dst`` by digit from the positions ``start`` (advanced)."""
    for k in range(s, e):
        d = (src[k] >> sh) & 2047
        dst[start[d]] = src[k]
        start[d] += 1


@compiled
def _grid_occupied(keys, shift, occ):
    """Set the bit of every cell holding one of ``keys``."""
    for r in range(keys.shape[0]):
        c = keys[r] >> (shift + 1)
        occ[c >> 6] |= np.uint64(1) << np.uint64(c & 63)


@compiled
def _grid_in_cells(lkeys, keys, shift):
    """Move the keys of ``lkeys`` whose cell holds one of the sorted ``keys`` to
    its front, in order (binary search); returns their number."""
    total = keys.shape[0]
    w = 0
    for r in range(lkeys.shape[0]):
        c = lkeys[r] >> (shift + 1)
        a, z = 0, total
        while a < z:                             # first current key of cell >= c
            mid = (a + z) >> 1
            if (keys[mid] >> (shift + 1)) < c:
                a = mid + 1
            else:
                z = mid
        if a < total and (keys[a] >> (shift + 1)) == c:
            lkeys[w] = lkeys[r]
            w += 1
    return w


@compiled
def _grid_merged(keys, lkeys, shift):
    """Stable merge by ``key >> shift``: the current level's entries first."""
    total, w = keys.shape[0], lkeys.shape[0]
    merged = np.empty(total + w, np.int64)
    i, j, o = 0, 0, 0
    while i < total or j < w:
        if j >= w or (i < total and (keys[i] >> shift) <= (lkeys[j] >> shift)):
            merged[o] = keys[i]
            i += 1
        else:
            merged[o] = lkeys[j]
            j += 1
        o += 1
    return merged


@compiled
def _grid_cell_start(keys, p, shift):
    """The first entry at or after ``p`` that starts a cell (``len(keys)`` if none)."""
    n = keys.shape[0]
    while 0 < p < n and (keys[p] >> (shift + 1)) == (keys[p - 1] >> (shift + 1)):
        p += 1
    return p


@compiled
def _grid_rows(keys, act, row_bits, shift, s, e, first, face, counts):
    """Corner bits, face and pair count of the entries ``s .. e - 1`` (whole cells)."""
    total = keys.shape[0]
    mask = (np.int64(1) << row_bits) - 1
    start = s
    for p in range(s, e):
        key = keys[p]
        first[p] = key & 7
        face[p] = act[(key >> 3) & mask]
        if p == total - 1 or (keys[p + 1] >> (shift + 1)) != (key >> (shift + 1)):
            for q in range(start, p + 1):        # the cell ends at p
                if ((keys[q] >> shift) & 1) == 0:
                    counts[q] = p - q
            start = p + 1


@compiled
def _grid_cuts(counts, chunk):
    """Entry bounds of tasks of about ``chunk`` pairs."""
    total = counts.shape[0]
    # two passes (count, then fill): no array of one slot per entry for the cuts
    nc = 1
    acc = 0
    last = 0
    for p in range(total):
        acc += counts[p]
        if acc >= chunk:
            nc += 1
            acc = 0
            last = p + 1
    if last != total:
        nc += 1
    cuts = np.empty(nc, np.int64)
    cuts[0] = 0
    k = 1
    acc = 0
    for p in range(total):
        acc += counts[p]
        if acc >= chunk:
            cuts[k] = p + 1
            k += 1
            acc = 0
    if cuts[k - 1] != total:
        cuts[k] = total
    return cuts


@compiled
def _sorted_by_high_bits(keys, shift, bits):
    """Keys stably sorted by ``keys >> shift`` (``bits`` bits; keys >= 0).

    An LSD radix sort (11-bit digits): the entries of a cell keep their
    input order, where a full sort would order them by the low bits too; the
    pairs found do not depend on the order inside a cell.
    """
    return _radix_by_high_bits(keys.copy(), shift, bits)


@compiled
def _sorted_by_high_bits_inplace(keys, shift, bits):
    """:func:`_sorted_by_high_bits` using ``keys`` as scratch (it is overwritten):
    one array of the size of ``keys`` less at the peak."""
    return _radix_by_high_bits(keys, shift, bits)


@helper
def _radix_by_high_bits(src, shift, bits):
    """The radix passes of :func:`_sorted_by_high_bits` on ``src`` (overwritten);
    returns ``src`` or the scratch array, whichever holds the result."""
    n = src.shape[0]
    dst = np.empty_like(src)
    count = np.empty(2048, dtype=np.int64)
    done = 0
    while done < bits:
        count[:] = 0
        sh = shift + done
        for k in range(n):
            count[(src[k] >> sh) & 2047] += 1
        total = 0
        for d in range(2048):
            c = count[d]
            count[d] = total
            total += c
        for k in range(n):
            d = (src[k] >> sh) & 2047
            dst[count[d]] = src[k]
            count[d] += 1
        src, dst = dst, src
        done += 11
    return src


@compiled
def _fan_term_loops(V, F, plane, tol, active, N, v0, v1, block, cos_min, total, spread, shortest,
                    sin_min, q_min, rho, longest, t):
    """:func:`_corner_terms` and their scatter in one loop, for the corners at
    vertices ``v0 .. v1 - 1`` of the active faces, in the numpy path's order
    (blocks of ``block`` faces, corner by corner within a block): the same
    per-vertex values wherever the vertex has no degenerate face (the others
    are not separated anyway).  ``N``: the unit vertex normals, ``(n, 3)``."""
    m = F.shape[0]
    for s in range(0, m, block):
        e = min(s + block, m)
        for k in range(3):
            for f in range(s, e):
                p = F[f, k]
                if p < v0 or p >= v1 or not active[f]:
                    continue
                i0, i1, i2 = F[f, 0], F[f, 1], F[f, 2]
                # edge j from corner j to corner j + 1
                ax, ay, az = V[i1, 0] - V[i0, 0], V[i1, 1] - V[i0, 1], V[i1, 2] - V[i0, 2]
                bx, by, bz = V[i2, 0] - V[i1, 0], V[i2, 1] - V[i1, 1], V[i2, 2] - V[i1, 2]
                cx, cy, cz = V[i0, 0] - V[i2, 0], V[i0, 1] - V[i2, 1], V[i0, 2] - V[i2, 2]
                l0 = np.sqrt(ax * ax + ay * ay + az * az)
                l1 = np.sqrt(bx * bx + by * by + bz * bz)
                l2 = np.sqrt(cx * cx + cy * cy + cz * cz)
                big = max(max(l0, l1), l2)
                nf0, nf1, nf2 = plane[f, 0], plane[f, 1], plane[f, 2]
                wx, wy, wz = ay * cz - az * cy, az * cx - ax * cz, ax * cy - ay * cx
                double_area = abs(wx * nf0 + wy * nf1 + wz * nf2)
                if k == 0:
                    A0, A1, A2, B0, B1, B2, la, lb, lo = ax, ay, az, cx, cy, cz, l0, l2, l1
                elif k == 1:
                    A0, A1, A2, B0, B1, B2, la, lb, lo = bx, by, bz, ax, ay, az, l1, l0, l2
                else:
                    A0, A1, A2, B0, B1, B2, la, lb, lo = cx, cy, cz, bx, by, bz, l2, l1, l0
                if double_area == 0.0 or la * lb == 0.0 or lo * big == 0.0:
                    cos_min[p] = np.nan          # (rounding) no bound: not separated
                    continue
                n0, n1, n2 = N[p, 0], N[p, 1], N[p, 2]
                cos_n = n0 * nf0 + n1 * nf1 + n2 * nf2
                AB = -(A0 * B0 + A1 * B1 + A2 * B2)
                NA = n0 * A0 + n1 * A1 + n2 * A2
                NB = -(n0 * B0 + n1 * B1 + n2 * B2)
                sector = np.arctan2(double_area * cos_n, AB - NA * NB)
                q = double_area / (lo * big)
                half_sin = np.sqrt(-_nan_min(-(0.5 - 0.5 * AB / (la * lb)), -0.0))
                r = (la + lb) / double_area
                cos_min[p] = _nan_min(cos_min[p], cos_n)
                total[p] += sector
                spread[p] = _nan_min(spread[p], _nan_min(sector, np.pi - sector))
                shortest[p] = _nan_min(shortest[p], la)
                sin_min[p] = _nan_min(sin_min[p], half_sin)
                q_min[p] = _nan_min(q_min[p], q)
                rho[p] = -_nan_min(-rho[p], -r)
                longest[p] = -_nan_min(-longest[p], -big)
                t[p] = -_nan_min(-t[p], -tol[f])


@compiled
def _normal_sums(F, plane, v0, v1, N, count):
    """For the vertices ``v0 .. v1 - 1``: ``N[a, v]``, the sum of axis ``a`` of
    the unit normals of the faces at ``v`` and ``count[v]`` their number, as
    ``sum(np.bincount(F[:, k], weights=plane[:, a]) for k in range(3))`` and
    ``sum(np.bincount(F[:, k]) ...)`` give them (per corner column a sum in
    face order, then the three columns added to ``0`` in order)."""
    m = F.shape[0]
    acc = np.empty((v1 - v0, 3))                 # one column's sums at a time
    for v in range(v0, v1):
        count[v] = 0
    for k in range(3):
        acc[:] = 0.0
        for f in range(m):
            p = F[f, k]
            if p < v0 or p >= v1:
                continue
            for a in range(3):
                acc[p - v0, a] += plane[f, a]
            count[p] += 1
        for v in range(v0, v1):
            for a in range(3):
                if k == 0:
                    N[a, v] = 0.0 + acc[v - v0, a]
                else:
                    N[a, v] = N[a, v] + acc[v - v0, a]


@compiled
def _scatter_fan_terms(c, cos_n, sector, rim, length, half_sin, q, r, big, tol,
                       cos_min, total, spread, shortest, sin_min, q_min, rho, longest, t):
    """The scatter of :func:`_separated_fans` for one corner column of a block:
    ``np.minimum.at`` / ``np.maximum.at`` / ``np.add.at`` as one loop (the same
    order of additions; NaN propagates as in ``np.minimum``)."""
    for k in range(c.shape[0]):
        v = c[k]
        cos_min[v] = _nan_min(cos_min[v], cos_n[k])
        total[v] += sector[k]
        spread[v] = _nan_min(spread[v], rim[k])
        shortest[v] = _nan_min(shortest[v], length[k])
        sin_min[v] = _nan_min(sin_min[v], half_sin[k])
        q_min[v] = _nan_min(q_min[v], q[k])
        rho[v] = -_nan_min(-rho[v], -r[k])
        longest[v] = -_nan_min(-longest[v], -big[k])
        t[v] = -_nan_min(-t[v], -tol[k])


@helper
def _nan_min(a, b):
    """``np.minimum(a, b)``: NaN when either is NaN."""
    if a != a or b != b:
        return a + b
    return a if a <= b else b


@helper
def _pair_hits(i, j, F, V, plane, tol, E):
    """:func:`_intersecting` for one pair (compiled inside :func:`_pair_loops`)."""
    shA = np.zeros(3, np.bool_)
    shB = np.zeros(3, np.bool_)
    for a in range(3):
        for b in range(3):
            if F[i, a] == F[j, b]:
                shA[a] = True
                shB[b] = True
    ns = int(shA[0]) + int(shA[1]) + int(shA[2])
    if ns >= 3:
        return False
    t = max(tol[i], tol[j])
    PA = np.empty((3, 3))
    PB = np.empty((3, 3))
    for k in range(3):
        for c in range(3):
            PA[k, c] = V[F[i, k], c]
            PB[k, c] = V[F[j, k], c]
    dA = np.empty(3)
    dB = np.empty(3)
    for k in range(3):
        dA[k] = PA[k, 0] * plane[j, 0] + PA[k, 1] * plane[j, 1] + PA[k, 2] * plane[j, 2] - plane[j, 3]
        dB[k] = PB[k, 0] * plane[i, 0] + PB[k, 1] * plane[i, 1] + PB[k, 2] * plane[i, 2] - plane[i, 3]
    rejA = _one_side(dA, shA, t)
    rejB = _one_side(dB, shB, t)
    if ns == 2:
        if rejA and rejB:
            return False
    elif rejA or rejB:
        return False
    if ns == 2:
        ka = 0 if not shA[0] else (1 if not shA[1] else 2)    # corner off the shared edge
        kb = 0 if not shB[0] else (1 if not shB[1] else 2)
        side_b = _edge_distance_at(E, i, (ka + 1) % 3, PB[kb, 0], PB[kb, 1], PB[kb, 2])
        side_a = _edge_distance_at(E, j, (kb + 1) % 3, PA[ka, 0], PA[ka, 1], PA[ka, 2])
        return ((abs(dB[kb]) <= t and side_b > t) or (abs(dA[ka]) <= t and side_a > t))
    coplanar = ((abs(dA[0]) <= t and abs(dA[1]) <= t and abs(dA[2]) <= t)
                or (abs(dB[0]) <= t and abs(dB[1]) <= t and abs(dB[2]) <= t))
    if coplanar:
        if ns == 1:
            ka = 0 if shA[0] else (1 if shA[1] else 2)            # the shared corner
            kb = 0 if shB[0] else (1 if shB[1] else 2)
            return _rays_in_wedge(E, i, ka, PB, kb, t) or _rays_in_wedge(E, j, kb, PA, ka, t)
        return not (_separated_by_edge(E, i, PB, t) or _separated_by_edge(E, j, PA, t))
    return (_endpoint_inside(PA, dA, shA, E, j, t) or _endpoint_inside(PB, dB, shB, E, i, t))


@helper
def _one_side(d, sh, t):
    above = True
    below = True
    for k in range(3):
        above = above and (d[k] > t or sh[k])
        below = below and (d[k] < -t or sh[k])
    return above or below


@helper
def _edge_distance_at(E, f, k, x, y, z):
    """Signed distance of ``(x, y, z)``'s projection to edge ``k``'s line of face ``f``."""
    return E[f, 4 * k] * x + E[f, 4 * k + 1] * y + E[f, 4 * k + 2] * z - E[f, 4 * k + 3]


@helper
def _rays_in_wedge(E, f, k, PG, kg, t):
    """Does a ray to corner ``kg + 1`` or ``kg + 2`` of ``PG`` lie in face ``f``'s
    wedge at its corner ``k`` (edges ``k`` and ``k + 2``)?"""
    k2 = (k + 2) % 3
    for step in (1, 2):
        c = (kg + step) % 3
        x, y, z = PG[c, 0], PG[c, 1], PG[c, 2]
        if _edge_distance_at(E, f, k, x, y, z) >= -t and _edge_distance_at(E, f, k2, x, y, z) >= -t:
            return True
    return False


@helper
def _separated_by_edge(E, f, PY, t):
    """Is ``PY`` strictly outside the line of one edge of face ``f``?"""
    for k in range(3):
        outside = True
        for c in range(3):
            if not (E[f, 4 * k] * PY[c, 0] + E[f, 4 * k + 1] * PY[c, 1]
                    + E[f, 4 * k + 2] * PY[c, 2] - E[f, 4 * k + 3] < -t):
                outside = False
        if outside:
            return True
    return False


@helper
def _endpoint_inside(PX, dX, shX, E, fy, t):
    """:func:`_endpoints_inside` for one pair: a corner of ``X`` in ``Y``'s plane
    or a crossing of an edge of ``X`` with it, inside face ``fy`` and away from
    a corner ``X`` shares with it."""
    shared = shX[0] or shX[1] or shX[2]
    ks = 0 if shX[0] else (1 if shX[1] else 2)
    for k in range(3):
        k1 = (k + 1) % 3
        d = dX[k]
        d1 = dX[k1]
        if abs(d) <= t and not shX[k]:
            x, y, z = PX[k, 0], PX[k, 1], PX[k, 2]
        elif (d > t and d1 < -t) or (d < -t and d1 > t):
            s = d / (d - d1)
            x = PX[k, 0] + (PX[k1, 0] - PX[k, 0]) * s
            y = PX[k, 1] + (PX[k1, 1] - PX[k, 1]) * s
            z = PX[k, 2] + (PX[k1, 2] - PX[k, 2]) * s
        else:
            continue
        if shared:
            dx = x - PX[ks, 0]
            dy = y - PX[ks, 1]
            dz = z - PX[ks, 2]
            if not dx * dx + dy * dy + dz * dz > t * t:
                continue
        if (_edge_distance_at(E, fy, 0, x, y, z) >= -t and _edge_distance_at(E, fy, 1, x, y, z) >= -t
                and _edge_distance_at(E, fy, 2, x, y, z) >= -t):
            return True
    return False

