"""Displace a base by a height sampled on its refined surface: the shared relief core.

Used by ``geotex displace`` (every mapping), by the lapped relief
(:func:`geotex.image.displace.displace`) and by any caller holding a height
function.  Steps:

1. refine the base by edge splits to a target edge length
   (:func:`geotex.relief.subdivide.refined_by_edge_splits`: exact shape,
   creases kept, each refined corner knows its base face and barycentric
   coordinates);
2. direction of motion per refined vertex: the base's crease-aware corner
   normals (libigl ``per_corner_normals``, faces more than ``crease_angle``
   apart are not averaged) interpolated barycentrically over each base face
   (Phong), then averaged over the refined vertex's corners, so a vertex on
   a crease moves along the mean of its sides' normals and walls never tear;
3. the sampler gives a height ``h`` in ``[0, 1]`` per refined vertex (and an
   optional mask a weight ``w`` in ``[0, 1]``); optional uniform Laplacian
   low-pass steps;
4. offset ``depth * w * h`` (or ``depth * w * (h - 0.5)`` when symmetric:
   50 % grey is the base surface);
5. rounded as the output format stores it and judged like the verified
   export (:func:`geotex.printing.printable_stored_solid` is not imported
   here: the caller passes ``judge``); where the offset surface crosses
   itself the relief is halved on the crossing faces and two rings around
   them, at most ``RELIEF_ROUNDS`` times, then flattened there.  On large
   meshes the crossings near folded faces are looked for (locally) and
   lowered before the first verdict, so the judge usually finds none left
   and judges once (:func:`_likely_crossings`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import igl
import numpy as np
import scipy.sparse as sp

from geotex.check.intersections import self_intersecting_pairs
from geotex.errors import InputError
from geotex.jit import JIT_MIN_SIZE, compiled
from geotex.mesh.arrays import as_mesh_arrays
from geotex.options import finite_number, positive_number
from geotex.mesh.topology import first_use_order
from geotex.progress import report
from geotex.relief.subdivide import refined_by_edge_splits

__all__ = ["ReliefPoints", "ReliefResult", "displaced_solid", "relief_points",
           "edge_length_for_faces", "RELIEF_STAGES", "RELIEF_ROUNDS", "DEFAULT_MAX_FACES"]

#: Rounds of local relief reduction where the offset surface crosses itself.
RELIEF_ROUNDS = 6
#: Refined meshes from this many faces look for crossings near folds before the
#: first judge (:func:`_likely_crossings`); smaller ones are judged at once.
PRESEARCH_MIN_FACES = 200_000
#: That search looks at the faces within PRESEARCH_RINGS rings of the faces turned
#: by more than acos(PRESEARCH_COS) from their base orientation, widened by
#: PRESEARCH_GROW rings around every crossing it finds, and stops (leaving the
#: rest to the judge) where that is more than PRESEARCH_MAX_FRACTION of the faces.
PRESEARCH_COS = 0.3
PRESEARCH_RINGS = 2
PRESEARCH_GROW = 4
PRESEARCH_MAX_FRACTION = 0.25
#: Refuse refined meshes above this many faces unless asked.
DEFAULT_MAX_FACES = 6_000_000
#: Progress stages of :func:`displaced_solid`.
RELIEF_STAGES = ("refine", "normals", "heights", "displace", "decimate", "check")


@dataclass(frozen=True)
class ReliefPoints:
    """The refined surface a height sampler is asked about.

    Attributes
    ----------
    positions : numpy.ndarray, (p, 3) float64
        Refined vertices, on the base surface.
    normals : numpy.ndarray, (p, 3) float64
        Unit directions of motion (smoothed, crease-aware).
    face : numpy.ndarray, (p,) int64
        A base face each vertex lies in.
    bary : numpy.ndarray, (p, 3) float64
        Its barycentric coordinates in that face.
    faces : numpy.ndarray, (k, 3) int64
        Refined triangles.
    parent : numpy.ndarray, (k,) int64
        Base face of each refined triangle.
    base_vertices, base_faces : numpy.ndarray
        The base.
    """

    positions: np.ndarray
    normals: np.ndarray
    face: np.ndarray
    bary: np.ndarray
    faces: np.ndarray
    parent: np.ndarray
    base_vertices: np.ndarray
    base_faces: np.ndarray


@dataclass(frozen=True)
class ReliefResult:
    """A displaced solid and how it was made.

    Attributes
    ----------
    vertices : numpy.ndarray, (n, 3) float64
        As stored (rounded to ``precision``).
    faces : numpy.ndarray, (m, 3) int64
    report : CheckReport or None
        Verdict on exactly these arrays (``None`` when not judged).
    stats : dict
        Counts, edge length, reduced-relief rounds and seconds per stage.
    """

    vertices: np.ndarray
    faces: np.ndarray
    report: object
    stats: dict = field(default_factory=dict)


def _area(V, F) -> float:
    return 0.5 * float(np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]],
                                               V[F[:, 2]] - V[F[:, 0]]), axis=1).sum())


def edge_length_for_faces(V, F, faces: int) -> float:
    """Target edge length at which edge-split refinement gives about ``faces`` faces.

    Edge splitting ends with edges between half the target and the target;
    on the meshes measured (cylinders, Spot, spheres) the count is about
    ``area / (0.14 * L**2)``, within a factor of 1.5 (the count grows in
    steps: a uniform mesh quadruples per round).

    Returns
    -------
    float
    """
    V, F = as_mesh_arrays(V, F)
    n = int(faces)
    if n < 1:
        raise InputError(f"faces must be a positive integer, got {faces!r}")
    return math.sqrt(_area(V, F) / (0.14 * n))


def _vertex_normals(V, F, R, crease_angle: float) -> np.ndarray:
    CN = np.asarray(igl.per_corner_normals(V, F, float(crease_angle)), dtype=np.float64)
    CN = CN.reshape(-1, 3, 3)                            # (m, corner, xyz)
    B = R.corner_bary                                    # (k, corner, base corner)
    n = R.vertices.shape[0]
    if R.faces.size >= JIT_MIN_SIZE:
        N = np.zeros((n, 3))
        _corner_normal_sums(CN, B, R.parent, R.faces, N)
    else:
        P = CN[R.parent]                                 # (k, base corner, xyz)
        Nc = B[:, :, 0:1] * P[:, None, 0, :]             # (k, corner, xyz)
        Nc += B[:, :, 1:2] * P[:, None, 1, :]
        Nc += B[:, :, 2:3] * P[:, None, 2, :]
        del P
        idx = R.faces.ravel()
        N = np.empty((n, 3))
        for x in range(3):
            N[:, x] = np.bincount(idx, weights=Nc[:, :, x].ravel(), minlength=n)
    ln = np.linalg.norm(N, axis=1)
    bad = ~(ln > 1e-12)
    if bad.any():
        fn = np.asarray(igl.per_vertex_normals(R.vertices, R.faces), dtype=np.float64)
        N[bad] = fn[bad]
        ln[bad] = np.linalg.norm(N[bad], axis=1)
    N = N / np.where(ln > 0, ln, 1.0)[:, None]
    # degenerate base faces leave some vertices without a normal: they do not move
    N[~np.isfinite(N).all(axis=1)] = 0.0
    return N


@compiled
def _corner_normal_sums(CN, B, parent, F, N):
    """The numpy path of :func:`_vertex_normals` as one loop: each refined
    corner's Phong-interpolated base corner normal, summed into its vertex
    (the same products, sums and order: bit for bit), without the (k, 3, 3)
    temporaries."""
    for f in range(F.shape[0]):
        p = parent[f]
        for c in range(3):
            b0 = np.float64(B[f, c, 0])
            b1 = np.float64(B[f, c, 1])
            b2 = np.float64(B[f, c, 2])
            v = F[f, c]
            for x in range(3):
                t = b0 * CN[p, 0, x]
                t += b1 * CN[p, 1, x]
                t += b2 * CN[p, 2, x]
                N[v, x] += t


def relief_points(V, F, *, edge_length: float, crease_angle: float = 30.0,
                  max_faces: int = DEFAULT_MAX_FACES) -> ReliefPoints:
    """Refine a base and give the points and normals a height sampler works on.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    edge_length : float
        Longest refined edge (mesh units).
    crease_angle : float, optional
        Degrees; faces meeting at a larger dihedral angle keep their own
        normals (a crease).
    max_faces : int, optional
        Safety cap on the refined mesh.

    Returns
    -------
    ReliefPoints

    Raises
    ------
    InputError
        On a bad length or a result above ``max_faces``.
    """
    V, F = as_mesh_arrays(V, F)
    R = refined_by_edge_splits(V, F, edge_length, max_faces=max_faces, corner_bary=True)
    N = _vertex_normals(V, F, R, crease_angle)
    n = R.vertices.shape[0]
    face = np.empty(n, dtype=np.int64)
    bary = np.empty((n, 3), dtype=np.float64)
    idx = R.faces.ravel()
    face[idx] = np.repeat(R.parent, 3)
    bary[idx] = R.corner_bary.reshape(-1, 3)
    return ReliefPoints(R.vertices, N, face, bary, R.faces, R.parent, V, F)


def _smoothed(F, n, h, steps):
    if steps <= 0:
        return h
    e = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    A = sp.coo_matrix((np.ones(2 * e.shape[0]), (np.r_[e[:, 0], e[:, 1]],
                                                 np.r_[e[:, 1], e[:, 0]])), shape=(n, n)).tocsr()
    A.data[:] = 1.0
    deg = np.asarray(A.sum(axis=1)).ravel()
    M = sp.diags(1.0 / np.maximum(deg, 1.0)) @ A
    for _ in range(steps):
        h = 0.5 * h + 0.5 * (M @ h)
    return h


def _ring_ops(F):
    """``(at, grown)`` over the faces ``F``: ``at(mask)``, whether each face has a
    vertex in the vertex mask (the compiled path reuses one buffer: use it before
    the next call); ``grown(mask)``, the mask one ring wider (in place)."""
    if F.size >= JIT_MIN_SIZE:                   # one pass per ring, no temporaries
        fbuf = np.empty(F.shape[0], dtype=np.bool_)

        def at(mask):
            _faces_at(mask, F, fbuf)
            return fbuf

        def grown(mask):
            _grow_ring(mask, F, fbuf)
            return mask
        return at, grown
    cols = [np.ascontiguousarray(F[:, k]) for k in range(3)]

    def at(mask):
        return mask[cols[0]] | mask[cols[1]] | mask[cols[2]]

    def grown(mask):
        f = at(mask)
        for col in cols:
            mask[col[f]] = True
        return mask
    return at, grown


def _local_pairs(P, F, D, gain, local, precision):
    """Crossing pairs among the faces ``local`` of the relief ``P + gain * D`` as
    stored (rounded to ``precision``), as face indices into ``F``.  The search sees
    only these faces' vertices (its answer depends on them alone), so the relief
    is computed there, not over the whole mesh."""
    used, Fl = np.unique(F[local], return_inverse=True)
    Vr = (P[used] + gain[used, None] * D[used]).astype(precision).astype(np.float64)
    sub = self_intersecting_pairs(Vr, Fl.reshape(-1, 3))
    return local[np.asarray(sub, dtype=np.int64).reshape(-1, 2)] if len(sub) else ()


def _likely_crossings(P, F, D, precision):
    """Crossing pairs of the relief ``P + D`` found before any judge, near folds.

    Where the relief crosses itself the surface folds over a few refined edges
    (steep height steps on curved or concave parts): faces there turn far from
    their base orientation.  The faces within :data:`PRESEARCH_RINGS` rings of
    the faces turned by more than ``acos(PRESEARCH_COS)`` are searched (only
    them); around every crossing found the search widens by
    :data:`PRESEARCH_GROW` rings until no new pair appears.  Every pair found
    crosses under the judge's predicates (normalised on the searched faces, as
    in the lowering rounds' local searches); pairs elsewhere are the judge's to find (on Spot at 1.8M
    faces this finds all 959 of the judge's, so the first verdict is clean and
    no re-judge is needed).

    Returns
    -------
    numpy.ndarray, (k, 2) int64
    """
    n = P.shape[0]
    hit = np.zeros(n, dtype=np.bool_)
    _turned_faces_vertices(P, D, F, PRESEARCH_COS, hit)
    if not hit.any():
        return np.zeros((0, 2), dtype=np.int64)
    at, grown = _ring_ops(F)
    for _ in range(PRESEARCH_RINGS):
        hit = grown(hit)
    gain = np.ones(n)
    found = np.zeros((0, 2), dtype=np.int64)
    while True:
        local = np.flatnonzero(at(hit))
        if local.size > PRESEARCH_MAX_FRACTION * F.shape[0]:
            return found                         # most of the mesh: the judge's search
        pairs = _local_pairs(P, F, D, gain, local, precision)
        if len(pairs) <= found.shape[0]:         # the region only grows: no new pair
            return found
        found = np.asarray(pairs, dtype=np.int64)
        hit[F[np.unique(found)].ravel()] = True
        for _ in range(PRESEARCH_GROW):
            hit = grown(hit)


@compiled
def _turned_faces_vertices(P, D, F, cos_max, hit):
    """Mark the vertices of faces whose normal on ``P + D`` is more than
    ``acos(cos_max)`` from their normal on ``P``."""
    for f in range(F.shape[0]):
        a = F[f, 0]
        b = F[f, 1]
        c = F[f, 2]
        u0 = P[b, 0] - P[a, 0]
        u1 = P[b, 1] - P[a, 1]
        u2 = P[b, 2] - P[a, 2]
        v0 = P[c, 0] - P[a, 0]
        v1 = P[c, 1] - P[a, 1]
        v2 = P[c, 2] - P[a, 2]
        n0 = u1 * v2 - u2 * v1
        n1 = u2 * v0 - u0 * v2
        n2 = u0 * v1 - u1 * v0
        u0 = (P[b, 0] + D[b, 0]) - (P[a, 0] + D[a, 0])
        u1 = (P[b, 1] + D[b, 1]) - (P[a, 1] + D[a, 1])
        u2 = (P[b, 2] + D[b, 2]) - (P[a, 2] + D[a, 2])
        v0 = (P[c, 0] + D[c, 0]) - (P[a, 0] + D[a, 0])
        v1 = (P[c, 1] + D[c, 1]) - (P[a, 1] + D[a, 1])
        v2 = (P[c, 2] + D[c, 2]) - (P[a, 2] + D[a, 2])
        m0 = u1 * v2 - u2 * v1
        m1 = u2 * v0 - u0 * v2
        m2 = u0 * v1 - u1 * v0
        dot = n0 * m0 + n1 * m1 + n2 * m2
        ln = np.sqrt((n0 * n0 + n1 * n1 + n2 * n2) * (m0 * m0 + m1 * m1 + m2 * m2))
        if dot < cos_max * ln:
            hit[a] = True
            hit[b] = True
            hit[c] = True


def _lowered_where_crossing(P, F, D, gain, pairs, precision):
    """Lower the relief around crossing faces until they are clean locally.

    ``P + gain[:, None] * D`` is the relief (``D``: the full motion of every
    vertex).  The first search is the judge's (every pair, whole mesh); later
    rounds only search the faces within a few rings of the lowered region
    (the judge then judges again: the faces at moved vertices against the
    whole mesh, see :func:`geotex.check.report.recheck_moved`).  Rounds halve
    the relief on the crossing faces and two rings around them; after
    ``RELIEF_ROUNDS`` they flatten it on growing rings.
    """
    n = P.shape[0]
    gain = gain.copy()
    rounds = 0
    rings = 2
    at, grown = _ring_ops(F)

    while len(pairs) and rounds < 3 * RELIEF_ROUNDS:
        hit = np.zeros(n, dtype=bool)
        hit[F[np.unique(np.asarray(pairs).ravel())].ravel()] = True
        if rounds >= RELIEF_ROUNDS:                             # flatten, on wider rings
            rings += 1
        for _ in range(rings):
            hit = grown(hit)
        gain[hit] = 0.5 * gain[hit] if rounds < RELIEF_ROUNDS else 0.0
        rounds += 1
        near = hit.copy()
        for _ in range(4):
            near = grown(near)
        pairs = _local_pairs(P, F, D, gain, np.flatnonzero(at(near)), precision)
    return gain, rounds


@compiled
def _faces_at(mask, F, out):
    """``out[f]``: whether face ``f`` has a vertex in ``mask``."""
    for f in range(F.shape[0]):
        out[f] = mask[F[f, 0]] or mask[F[f, 1]] or mask[F[f, 2]]


@compiled
def _grow_ring(mask, F, fbuf):
    """Add to ``mask`` every vertex of a face that has a vertex in ``mask`` (one
    ring; the faces are found before any vertex is added)."""
    for f in range(F.shape[0]):
        fbuf[f] = mask[F[f, 0]] or mask[F[f, 1]] or mask[F[f, 2]]
    for f in range(F.shape[0]):
        if fbuf[f]:
            mask[F[f, 0]] = True
            mask[F[f, 1]] = True
            mask[F[f, 2]] = True


def displaced_solid(V, F, heights: Callable[[ReliefPoints], np.ndarray] | None = None, *,
                    depth: float, edge_length: float | None = None,
                    target_faces: int | None = None, symmetric: bool = False,
                    weights: Callable[[ReliefPoints], np.ndarray] | None = None,
                    smoothing: int = 0, crease_angle: float = 30.0,
                    max_faces: int = DEFAULT_MAX_FACES, decimate_to: int | None = None,
                    judge: Callable | None = None, fix_intersections: bool = True,
                    points: ReliefPoints | None = None, heights_array=None,
                    precision=np.float64, progress=None) -> ReliefResult:
    """Displace a refined copy of a base along smoothed normals by a sampled height.

    This is the public relief core ("displace this base by these heights"):
    give either a sampler ``heights(points) -> h`` or, with ``points`` from
    :func:`relief_points`, the array ``heights_array``.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        A closed manifold base for a printable result.
    heights : callable, optional
        ``heights(points: ReliefPoints) -> (p,) float`` in ``[0, 1]``.
    depth : float
        Relief depth (mesh units): the offset of height 1 (or, with
        ``symmetric``, the peak-to-peak relief around the surface).
    edge_length : float, optional
        Longest refined edge; default from ``target_faces``.
    target_faces : int, optional
        Wanted face count (sets ``edge_length`` by
        :func:`edge_length_for_faces`); default 1,000,000.
    symmetric : bool, optional
        Offset ``depth * (h - 0.5)``: 50 % grey stays on the surface.
    weights : callable, optional
        ``weights(points) -> (p,)`` in ``[0, 1]``: a mask (0 keeps the base);
        it may return ``None`` for "no mask".
    smoothing : int, optional
        Uniform Laplacian low-pass steps on ``h``.
    crease_angle : float, optional
        Degrees (see :func:`relief_points`).
    max_faces : int, optional
        Safety cap of the refined mesh.
    decimate_to : int, optional
        QEM-decimate the displaced mesh to this many faces (fast-simplification)
        when it has more.
    judge : callable, optional
        ``judge(V, F) -> (V_stored, F_stored, CheckReport)``, for example the
        verified export's ``printable_stored_solid``; used to find
        self-intersections and to return a verdict.  When its report lists
        every crossing pair in ``examples`` (``max_examples`` large) and
        keeps the faces' order, the first crossing search is skipped.
    fix_intersections : bool, optional
        Lower the relief where the judged solid crosses itself: halved on the
        crossing faces and two rings around them, up to ``RELIEF_ROUNDS``
        times, then flattened on growing rings; judged again once at the end.
        From ``PRESEARCH_MIN_FACES`` refined faces, crossings near folded
        faces are found and lowered this way before the first verdict.
    precision : type, optional
        Coordinates as the file stores them (``numpy.float32`` for STL): the
        crossings are looked for on these.
    points : ReliefPoints, optional
        Reuse a refinement (then ``edge_length``/``target_faces`` are ignored).
    heights_array : array_like, (p,) optional
        Heights for ``points`` instead of a sampler.
    progress : callable, optional
        Called with each of ``RELIEF_STAGES``.

    Returns
    -------
    ReliefResult

    Raises
    ------
    InputError
        Bad depth, sizes, or heights of the wrong shape.
    """
    d = positive_number(depth, name="depth")
    sec = {}
    t = time.perf_counter()
    report(progress, "refine")
    if points is None:
        V, F = as_mesh_arrays(V, F)
        if edge_length is None:
            edge_length = edge_length_for_faces(V, F, 1_000_000 if target_faces is None
                                                else target_faces)
        L = positive_number(edge_length, name="edge_length")
        points = relief_points(V, F, edge_length=L, max_faces=max_faces,
                               crease_angle=finite_number(crease_angle, name="crease_angle"))
        sec["refine"] = time.perf_counter() - t
    else:
        L = float("nan") if edge_length is None else float(edge_length)
    t = time.perf_counter()
    report(progress, "heights")
    P, Fr, N = points.positions, points.faces, points.normals
    n = P.shape[0]
    h = heights(points) if heights is not None else heights_array
    if h is None:
        raise InputError("give heights (a sampler) or heights_array")
    h = np.asarray(h, dtype=np.float64)
    if h.shape != (n,) or not np.isfinite(h).all():
        raise InputError(f"heights must be {n} finite values, got shape {h.shape}")
    h = _smoothed(Fr, n, np.clip(h, 0.0, 1.0), int(smoothing))
    off = d * ((h - 0.5) if symmetric else h)
    if weights is not None:
        w = weights(points)
        if w is not None:                         # None: no mask
            w = np.asarray(w, dtype=np.float64)
            if w.shape != (n,):
                raise InputError(f"weights must be {n} values, got shape {w.shape}")
            off = off * np.clip(w, 0.0, 1.0)
        del w
    # from here on only the positions, the motion and the faces are used: the
    # refinement's per-vertex face and barycentrics and the per-face parents
    # (~45 MB at 2M faces) are released before the check, where the memory peak is
    del h, points
    sec["heights"] = time.perf_counter() - t
    t = time.perf_counter()
    report(progress, "displace")
    # the full motion D = off * N (one array instead of two); a lowered relief
    # P + gain * D equals P + (off * gain) * N bit for bit, gain being 1, a power
    # of 2 or 0 (scaling by a power of 2 commutes with rounding)
    D = off[:, None] * N
    del off, N
    Fd = Fr
    refined_faces = int(Fr.shape[0])
    decimate = decimate_to is not None and Fd.shape[0] > int(decimate_to)
    if judge is not None and not decimate:
        # number the vertices by first use in the faces, as the stored form (and any
        # reader) numbers them: a judge that rounds and welds then gets back faces equal
        # to these and can share them instead of holding a second copy at the check
        order = first_use_order(Fd, n)
        inv = np.empty_like(order)
        inv[order] = np.arange(n, dtype=np.int64)
        Fd = inv[Fd]
        P, D = P[order], D[order]
        del order, inv, Fr
    Vd = None
    sec["displace"] = time.perf_counter() - t
    report(progress, "decimate")
    if decimate:
        import fast_simplification

        t = time.perf_counter()
        Vd, Fd = fast_simplification.simplify(P + D, Fd.astype(np.int32),
                                              target_count=int(decimate_to))
        Vd, Fd = np.asarray(Vd, np.float64), np.asarray(Fd, np.int64)
        sec["decimate"] = time.perf_counter() - t
        fix_intersections_here = False            # vertex ids no longer match the heights
    else:
        fix_intersections_here = fix_intersections
    rep = None
    rounds = 0
    if judge is not None:
        t = time.perf_counter()
        report(progress, "check")
        # the displaced vertices are handed over without a name kept here: a judge
        # that only needs their stored form can release them before its check
        gain = np.ones(n)
        if fix_intersections_here and Fd.shape[0] >= PRESEARCH_MIN_FACES:
            # lower the relief where it crosses itself near folds before the first
            # verdict: the whole-mesh judge then usually finds nothing left to lower
            # and no second (local) verdict is needed
            pairs = _likely_crossings(P, Fd, D, precision)
            if len(pairs):
                gain, rounds = _lowered_where_crossing(P, Fd, D, gain, pairs, precision)
        Vs, Fs, rep = judge(P + gain[:, None] * D if Vd is None else Vd, Fd)
        passes = 0
        while (fix_intersections_here and not rep.printable and rep.self_intersecting_pairs
               and passes < 4):
            # a judge that lists every crossing pair saves a whole-mesh search
            ex = rep.examples.get("self_intersecting_pairs") if Fs.shape == Fd.shape else None
            if ex is not None and len(ex) == rep.self_intersecting_pairs:
                pairs = np.asarray(ex, dtype=np.int64).reshape(-1, 2)
            else:
                pairs = self_intersecting_pairs(
                    (P + gain[:, None] * D).astype(precision).astype(np.float64), Fd)
            gain, r = _lowered_where_crossing(P, Fd, D, gain, pairs, precision)
            rounds += r
            passes += 1
            Vs, Fs, rep = judge(P + gain[:, None] * D, Fd)
        Vd, Fd = Vs, Fs
        sec["check"] = time.perf_counter() - t
    elif Vd is None:
        Vd = P + D
    stats = {"faces": int(Fd.shape[0]), "vertices": int(Vd.shape[0]),
             "refined_faces": refined_faces, "edge_length": L,
             "relief_reduced_rounds": rounds,
             "seconds": {k: round(v, 3) for k, v in sec.items()}}
    return ReliefResult(np.ascontiguousarray(Vd), np.ascontiguousarray(Fd), rep, stats)
