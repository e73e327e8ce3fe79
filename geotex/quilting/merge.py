"""Merging two overlapping closed elements: graph cut, weld (or Laplacian pull and stitch).

Element ``A`` (already in the texture; may carry fixed vertices) and element
``B`` (from the newly placed exemplar copy) overlap.  The merge:

0. **Alignment and correspondence** (``align``).  The part of ``B`` over
   the footprint overlap is translated onto ``A`` by ICP in the plane and
   the two meet half way (``B`` goes all the way when ``A`` has fixed
   vertices): the paper's "deform toward the midpoints" for elements that
   are copies of each other.  They correspond only when they are one
   element: the shift is small (position: at most ``max_shift`` of ``B``'s
   narrow width) and, after it, the two surfaces coincide over the common
   box of their footprints, seen from both sides (shape: ``match_fraction``
   of the vertices of each within ``match_tol`` of the other, or inside
   it).  ICP alone
   fits the few vertices of ``B`` over the overlap of two neighbouring
   elements well enough; fusing those made the two-bump elements of the
   tile sets (normal jumps of 130-180 degrees at their seams).  If
   they then coincide (``B``'s vertices inside the domain within
   ``same_tol`` of the footprint, RMS), ``A`` is kept alone.  Pairs that do
   not correspond are dropped with ``corresponding_only``; so are
   corresponding pairs that the overlap rule cannot cut.
1. **Covered vertices.**  A vertex of ``A`` is *covered* when a probe point
   just outside ``A`` (along its normal) lies inside ``B`` (winding number);
   a vertex of ``B`` when a probe just *inside* ``B`` lies inside ``A``.  The
   asymmetric probes break ties on coplanar parts (flat bottoms standing on
   the same plane): there ``A`` keeps its faces and ``B`` gives them up.
   Vertices of ``B`` outside the output domain count as covered.
2. **Graph cut per element.**  Dual graph of the element's triangles, edge
   weight ``(1 + |v_i - v_j| / h)(1 + (d(v_i) + d(v_j)) / h)`` over the shared
   edge ``(v_i, v_j)``, ``d`` the distance to the other element, ``h`` the mean
   edge length (the paper's weight made scale free).  Triangles with a
   covered vertex, triangles crossing the other element's surface and
   triangles of ``B`` leaving the domain are tied to SINK (removed);
   triangles farther than ``band_rings`` face rings from them, and triangles
   touching a fixed vertex, are tied to SOURCE (kept).  The cut chooses the
   seam inside the band, where the elements are close and the cut is short.
   Each piece keeps only faces clear of the other element, so the two
   pieces cannot cross each other.
   *Corresponding elements* (the alignment was accepted: two copies of one
   element, two pieces of one strand) coincide where they overlap, so
   "covered" is ambiguous there; they are cut by the paper's overlap rule
   instead (:func:`_corresponding_cut`): the coinciding zone is free, the
   part without counterpart is SOURCE, the part inside the other element
   and where the other element goes on is SINK; ``A`` is cut first, where
   the two surfaces coincide *and face the same way* (eq. 8's cost plus the
   angle between the two surfaces, ``tilt_cost``), and ``B`` on ``A``'s
   seam (its cost is the distance to that seam), giving up what ``A`` kept.
3. **Weld** (corresponding pairs).  The kept pieces' boundary loops are
   paired by proximity; optionally (``zone > 0``) both pieces are first
   deformed toward the midpoints of corresponding points over the overlap
   zone (:func:`_toward_midpoints`, the paper's eqs. 6-7).  Every loop
   vertex moves to the midpoint between itself and its corresponding point
   on the partner loop, the point at the same arc-length parameter
   (:func:`geotex.quilting.seam.matched_on_loops`; ``B`` all the way when
   ``A`` is held), loop vertices that then meet become one
   vertex, and the two loops are interleaved along the shortest-diagonal
   walk and zipped (:func:`geotex.quilting.seam.zip_loops`): the boundary
   faces become fans, the pieces share the seam, gap 0, no strip.
4. **Pull and stitch** (other pairs, or when the weld does not validate).
   Every loop vertex gets the target "a fraction ``pull / 2`` of the way to
   the closest point of the partner loop" (``pulls`` are tried in turn,
   0.5 first: full strength would make the strip degenerate), each piece is
   deformed by :func:`geotex.quilting.deform.laplacian_deformed` (uniform
   Laplacian) with fixed vertices and vertices far from the seam held, and
   each loop pair is closed by a strip with the shortest total diagonals
   (:mod:`geotex.quilting.seam`).  Every result (weld or strip) is
   validated: one closed, edge- and vertex-manifold, consistently oriented
   component with positive volume, no degenerate faces and no
   self-intersection (:func:`geotex.check.intersections.self_intersecting_pairs`);
   fixed vertices are untouched and no vertex moved out of the domain.
5. **Fallback.**  If any step fails, the two (aligned, undeformed) elements
   are united with manifold3d (exact boolean).  If ``B`` leaves the domain,
   or the union would lose a fixed vertex or a cap, ``B`` is dropped and
   ``A`` is returned as it was.  Never an open element.

How this differs from the paper.  The paper deforms both corresponding
elements toward the midpoints of corresponding vertices (Laplacian editing,
tile boundary fixed), then cuts (eq. 8) and stitches along the cut paths.
Here the correspondence is first a rigid half-way shift (ICP of the
overlapping part), the cut comes *before* any deformation ("inside the other
element" is only well defined while the surfaces still cross cleanly), and
by default only the cut loops are moved (to their common midpoint curve)
and welded: the midpoint Laplacian editing of the whole overlap zone is
implemented (``zone``) but off, because on the weave quilts it did not
lower the normal jump (mean over seam edges 9.6 / 7.1 / 8.7 degrees with
``zone=1`` against 9.7 / 7.9 / 5.4 without, with the cut of that time) and
shrank merged strands by 0.6-2 % of their volume.  The cut of ``A`` adds
the angle between the two surfaces to eq. 8's distance (the paper uses the
distance only) and a share of ``A``'s own dihedral angle at the cut
edge (``crease_cost``), ``B`` is cut on ``A``'s seam, and the loops meet at
points of equal arc-length parameter: then every join of 36 weave quilts
(three sizes, seeds 0-11) welds, and the seams bend by 1.5-2.1 degrees on
average, at most 3.1 (``benchmarks/results/quilting.md`` 4c, 4d).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import igl
import numpy as np
from scipy.spatial import cKDTree

from geotex.check.intersections import self_intersecting_pairs
from geotex.errors import InputError
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.geometry import face_normals, mean_edge_length
from geotex.mesh.solid import arrays_of_manifold, manifold_of
from geotex.mesh.topology import edge_topology
from geotex.quilting.deform import laplacian_deformed
from geotex.quilting.icp import ClosestPoints, icp_translation
from geotex.quilting.mincut import min_cut_keep
from geotex.quilting.elements import caps_like, closed_element_ok
from geotex.quilting.seam import (boundary_loops, closest_on_polyline, matched_on_loops,
                                 pair_loops, seam_normal_jumps, strip_between, zip_loops)

__all__ = ["MergeResult", "merge_elements"]


@dataclass
class MergeResult:
    """Outcome of :func:`merge_elements`.

    Attributes
    ----------
    vertices : numpy.ndarray, (n, 3) float64
    faces : numpy.ndarray, (m, 3) int64
        One closed element, or both elements side by side when ``status`` is
        ``"separate"``.
    fixed : numpy.ndarray, (n,) bool
        Output vertices that are fixed vertices of ``A`` (bit-exact).
    status : str
        ``"stitched"`` (graph cut + stitch), ``"union"`` (manifold3d fallback),
        ``"separate"`` (they do not touch: both returned unchanged),
        ``"absorbed"`` (one lies inside the other: the outer one returned),
        ``"dropped"`` (``B`` could not be merged and was discarded).
    seam_gap : float
        Largest distance between a loop vertex and its partner loop after the
        Laplacian pull (``nan`` unless stitched).
    seam_normal_jump : float
        Largest angle (degrees) between the face normals on either side of
        the seam, across the strip (``nan`` unless stitched).
    seam_normal_jump_mean : float
        Mean of that angle over the seam edges (``nan`` unless stitched).
    corresponding : bool
        The pair was merged as corresponding elements (alignment accepted).
    reason : str
        Why the stitch was not used (empty when stitched).
    parts : int
        Number of elements in the result (2 when ``"separate"``).
    cap : numpy.ndarray, (m,) bool
        Faces that are caps of ``A`` (see ``cap_a``).
    """

    vertices: np.ndarray
    faces: np.ndarray
    fixed: np.ndarray
    status: str
    seam_gap: float = float("nan")
    seam_normal_jump: float = float("nan")
    seam_normal_jump_mean: float = float("nan")
    seam_edges: int = 0
    corresponding: bool = False
    reason: str = ""
    parts: int = field(default=1)
    cap: np.ndarray = None

    def __post_init__(self):
        if self.cap is None:
            self.cap = np.zeros(self.faces.shape[0], dtype=bool)


def _compact(V, F, keep_faces, fixed):
    F2 = F[keep_faces]
    used = np.zeros(V.shape[0], dtype=bool)
    used[F2.ravel()] = True
    remap = np.cumsum(used) - 1
    return V[used], remap[F2], fixed[used]


def _same_a(VA, FA, fixA, capA, status, reason=""):
    return MergeResult(VA, FA, fixA, status, reason=reason, cap=capA)


def _covered(V, F, N, other_V, other_F, sign: float, eps: float) -> np.ndarray:
    probes = V + sign * eps * N
    return igl.winding_number(other_V, other_F, probes) > 0.5


def _cut(V, F, covered, dist, fixed, force_sink, band_rings: int):
    """Keep-mask of faces by the graph cut described in the module docstring."""
    sink = covered[F].any(axis=1) | force_sink
    near = np.zeros(V.shape[0], dtype=bool)
    near[F[sink].ravel()] = True
    band = sink.copy()
    for _ in range(band_rings):
        band = near[F].any(axis=1)
        near[F[band].ravel()] = True
    source = ~band | fixed[F].any(axis=1)
    return _dual_cut(V, F, dist, source, sink & ~source)


def _dual_cut(V, F, dist, source, sink, crease=0.0):
    """Graph cut of the dual graph with the paper's weights; keep-mask of faces.

    ``crease`` > 0 adds that many times the dihedral angle (radians) of the
    mesh edge to the distance factor of its weight: a cut along a crease
    makes a seam that bends as much.
    """
    m = F.shape[0]
    if not sink.any():
        return np.ones(m, dtype=bool)
    if not source.any():
        return np.zeros(m, dtype=bool)
    topo = edge_topology(F, V.shape[0])
    ef = topo.edge_faces()
    inner = (topo.face_count == 2)
    E = topo.edges[inner]
    pairs = ef[inner]
    h = float(np.linalg.norm(V[topo.edges[:, 0]] - V[topo.edges[:, 1]], axis=1).mean()) or 1.0
    length = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1) / h
    extra = 0.0
    if crease > 0:
        N = face_normals(V, F)
        c = np.einsum("ij,ij->i", N[pairs[:, 0]], N[pairs[:, 1]])
        extra = crease * np.arccos(np.clip(c, -1.0, 1.0))
    w = (1.0 + length) * (1.0 + (dist[E[:, 0]] + dist[E[:, 1]]) / h + extra)
    return min_cut_keep(m, pairs, w, source=source, sink=sink)


def _corresponding_cut(VA, FA, VB, FB, NA, NB, fixA, out_b, eps, band_rings,
                       tilt_cost=1.0, crease_cost=0.5):
    """Keep-masks of faces for two elements that coincide where they overlap.

    The paper's rule for corresponding elements (copies of one element, or
    two pieces of one strand after the alignment shift): where the surfaces
    coincide (closer than ``tau``, a quarter of the mean edge length) the
    cut may run; the part of an element that has no counterpart (farther
    than ``tau`` from the other and not inside it) or lies outside the two
    elements' common box is kept (SOURCE); the part inside the other element
    (an end cap inside the other strand) and the vertices whose counterpart
    on the other element lies outside the common box go (SINK).  ``A`` is
    cut first, with the paper's weight over the distance to ``B`` plus
    ``tilt_cost`` mean edge lengths per radian between ``A``'s vertex normal
    and ``B``'s surface there: two strand pieces that coincide in position
    but slope differently (a strand of one copy running over, the other's
    under) make a crease of 15-20 degrees at a seam cut there; and
    ``crease_cost`` times the dihedral angle of ``A``'s edge (in the factor
    of the distances): a seam along a ring where the strand itself creases
    bends by that crease (one join of the weave quilt 2x1.5 -> 4x3, seed
    3: 23 degrees on all twelve seam edges; 1.7 with ``crease_cost=0.5``).  ``B`` then
    gives up every face whose counterpart on ``A`` was kept (except on
    ``A``'s seam itself, closer than ``tau``) and may cut only within
    ``band_rings`` of its mean edge lengths of ``A``'s seam, at the least
    distance from that seam: the two loops then lie on one ring (weave
    quilts: loops at most 0.04 apart along the strand, mostly under 0.008;
    before, most joins were one ring apart, 0.06, some two), so the weld
    moves them by almost nothing.  Returns ``None`` when the elements do not
    coincide anywhere (the general path then applies).
    """
    h = float(np.mean([mean_edge_length(VA, FA, per_face=True) or 1.0,
                       mean_edge_length(VB, FB, per_face=True) or 1.0]))
    tau = 0.25 * h
    dA2, fA, _ = ClosestPoints(VB, FB).query(VA)
    dB2, fB, _ = ClosestPoints(VA, FA).query(VB)
    dA, dB = np.sqrt(dA2), np.sqrt(dB2)
    nearA, nearB = dA < tau, dB < tau
    if nearA.sum() < 3 or nearB.sum() < 3:
        return None
    lo = np.maximum(VA.min(0), VB.min(0))[:2] - tau
    hi = np.minimum(VA.max(0), VB.max(0))[:2] + tau
    boxA = ((VA[:, :2] >= lo) & (VA[:, :2] <= hi)).all(axis=1)
    boxB = ((VB[:, :2] >= lo) & (VB[:, :2] <= hi)).all(axis=1)
    covA = _covered(VA, FA, NA, VB, FB, +1.0, eps)
    covB = _covered(VB, FB, NB, VA, FA, -1.0, eps)
    # A: keep what B has no counterpart for, remove A inside B and A where B goes on
    excl_B_face = (~boxB)[FB].any(axis=1)
    sink_v = (~nearA & covA) | (nearA & excl_B_face[fA])
    source_v = ((~nearA & ~covA) | ~boxA) & ~sink_v
    sinkA = sink_v[FA].any(axis=1)
    sourceA = (source_v[FA].all(axis=1) & ~sinkA) | fixA[FA].any(axis=1)
    costA = dA
    if tilt_cost > 0:
        # eq. 8 with the surfaces' directions: a seam where the two elements
        # coincide but slope differently creases the merged element
        cosang = np.einsum("ij,ij->i", NA, face_normals(VB, FB)[fA])
        costA = dA + tilt_cost * h * np.arccos(np.clip(cosang, -1.0, 1.0))
    keep_a = _dual_cut(VA, FA, costA, sourceA, sinkA & ~sourceA, crease=crease_cost)
    if keep_a.all() or not keep_a.any():
        return None
    # B: give up what A kept, cut next to A's seam (within band_rings
    # of B's own mean edge lengths of it, whatever A's triangles are like)
    on_kept = np.zeros(VA.shape[0], bool)
    on_kept[FA[keep_a].ravel()] = True
    on_gone = np.zeros(VA.shape[0], bool)
    on_gone[FA[~keep_a].ravel()] = True
    seam = VA[on_kept & on_gone]
    if seam.shape[0] == 0:
        return None
    hB = mean_edge_length(VB, FB, per_face=True) or 1.0
    to_seam = cKDTree(seam).query(VB)[0]
    near_seam = to_seam <= band_rings * hB
    sink_v = (~nearB & covB) | (nearB & keep_a[fB] & (to_seam > tau)) | out_b
    free_v = nearB & near_seam & ~sink_v
    source_v = ~sink_v & ~free_v
    sinkB = sink_v[FB].any(axis=1)
    sourceB = source_v[FB].all(axis=1) & ~sinkB
    keep_b = _dual_cut(VB, FB, to_seam, sourceB, sinkB)
    return keep_a, keep_b


def _outside_domain(V, domain):
    if domain is None:
        return np.zeros(V.shape[0], dtype=bool)
    x0, y0, x1, y1 = domain
    return (V[:, 0] < x0) | (V[:, 0] > x1) | (V[:, 1] < y0) | (V[:, 1] > y1)


def merge_elements(VA, FA, VB, FB, *, fixed_a=None, domain=None, band_rings: int = 1,
                   mu: float = 10.0, pull_radius: float = 3.0,
                   pulls=(0.5, 0.25, 0.0), align: bool = True, max_shift: float = 0.25,
                   same_tol: float = 0.04, match_tol: float = 0.05,
                   match_fraction: float = 0.85, corresponding_only: bool = False,
                   cap_a=None, weld: bool = True, zone: float = 0.0,
                   weld_tol: float = 0.5, tilt_cost: float = 1.0,
                   crease_cost: float = 0.5) -> MergeResult:
    """Merge element ``B`` into element ``A`` (see the module docstring).

    Parameters
    ----------
    VA : array_like, (na, 3) float64
    FA : array_like, (ma, 3) int64
        Element already in the texture (closed, outward oriented).
    VB : array_like, (nb, 3) float64
    FB : array_like, (mb, 3) int64
        Element of the placed copy (closed, outward oriented).
    fixed_a : array_like (na,) bool, optional
        Vertices of ``A`` that must not move; they are kept and bit-exact.
    domain : tuple (xmin, ymin, xmax, ymax), optional
        Nothing of ``B`` may end up outside this rectangle.
    band_rings : int, optional
        Width, in face rings, of the free band in which the cut may move.
    mu : float, optional
        Weight of the loop targets in the Laplacian pull.
    pull_radius : float, optional
        Vertices farther than ``pull_radius`` mean edge lengths from the seam
        stay put during the pull.
    pulls : sequence of float, optional
        Pull strengths tried in turn until the stitched element validates:
        1 moves each loop vertex to the midpoint between itself and the
        partner loop, 0.5 half way there, 0 stitches the loops as cut.
        (Full strength makes the strip degenerate: the loops coincide.)
    align : bool, optional
        First move the two elements toward each other by the translation that
        best aligns the part of ``B`` over the footprint overlap onto ``A``
        (ICP in the plane): each goes half way,
        or ``B`` all the way when ``A`` has fixed vertices.  Corresponding
        elements then overlap as much as they can, as in the paper's midpoint
        deformation, and the merged element looks like one element.
    max_shift : float, optional
        Largest alignment shift, relative to the narrow width of ``B``'s
        footprint; larger shifts are not applied (the pair does not
        correspond).  Measured: the strand pieces of the weave quilts align
        with at most 0.14; the jittered studs that the tile builder fused
        before this limit (0.5 then) needed 0.45: neighbouring elements of
        the exemplar, similar in shape, not one element.
    match_tol : float, optional
        Largest RMS distance (relative to the narrow width) of ``B``'s
        overlapping vertices to ``A`` after alignment for the two to count
        as corresponding; otherwise no shift is applied.  Also the distance
        within which a vertex counts as on the other surface in the shape
        test (``match_fraction``).
    match_fraction : float, optional
        Shape test of the correspondence: over the common box of the two
        footprints, at least this fraction of ``A``'s vertices must lie on
        (within ``match_tol``) or inside ``B``, and of ``B``'s on or inside
        ``A``, after the shift (measured: 0.88-0.98 for strand pieces, 0.78
        for a neighbouring scale).
    same_tol : float, optional
        When, after alignment, the RMS distance of ``B``'s vertices inside the
        domain to ``A`` is below this fraction of ``B``'s footprint, the two
        are taken to be the same element and the (moved) ``A`` is returned
        alone (a frame half and the copy of its element, which goes on beyond
        the tile side, are the same element).
    cap_a : array_like (ma,) bool, optional
        Faces of ``A`` that only close a cut opening on the domain boundary
        (see :func:`geotex.quilting.elements.capped`); carried through to
        ``MergeResult.cap`` so that the caller can leave them out.
    weld : bool, optional
        Corresponding pairs: weld the cut loops into one shared seam
        (:func:`geotex.quilting.seam.zip_loops`; seam gap 0) before trying
        the Laplacian pull and strip.
    zone : float, optional
        Corresponding pairs, with ``weld``: vertices of each kept piece
        closer than ``zone`` mean edge lengths to the other element (and
        facing the same way) are first pulled toward the midpoints of
        corresponding points by Laplacian editing (the paper's eqs. 6-7;
        uniform Laplacian, weight ``mu``, held beyond ``pull_radius``).  0
        (the default) skips it: measured on the weave quilts it did not lower
        the normal jump and took 0.6-2 % of the volume (see
        ``benchmarks/results/quilting.md``).
    weld_tol : float, optional
        Loop vertices closer than this fraction of the loop edges to a vertex
        of the other loop become that vertex when welding.
    crease_cost : float, optional
        Corresponding pairs: the weight of a dual edge of ``A``'s cut grows
        by this many times the dihedral angle (radians) at the mesh edge, so
        the seam avoids rings where the element itself creases (0: off).
        Measured on 36 weave quilts (``benchmarks/results/quilting.md`` 4d):
        0.25 left one seam on a 69 degree crease, 0.5 none (largest seam
        jump 3.1 degrees), 1 pulled two cuts where the loops no longer pair
        up and two copies were dropped.
    tilt_cost : float, optional
        Corresponding pairs: the cut of ``A`` also pays this many mean edge
        lengths per radian of angle between the two surfaces, so the seam
        runs where they face the same way (0: distance only, the paper's
        eq. 8).  Measured on the weave quilts of
        ``benchmarks/bench_seams.py``: 0.5 and 1 give the same seams; 3 and
        more pull the cut into the overlap's ends, where the loops no longer
        pair up, and welds fail.
    corresponding_only : bool, optional
        When the pair does not correspond (see ``max_shift``, ``match_tol``,
        ``match_fraction``; tested at the ICP shift, which is applied only
        with ``align``) the two are different elements that merely collide;
        return ``B`` dropped instead of fusing them into one larger element.

    Returns
    -------
    MergeResult
    """
    VA, FA = as_mesh_arrays(VA, FA, allow_empty=False)
    VB, FB = as_mesh_arrays(VB, FB, allow_empty=False)
    fixA = np.zeros(VA.shape[0], bool) if fixed_a is None else np.asarray(fixed_a, bool).copy()
    fixB = np.zeros(VB.shape[0], bool)
    capA = np.zeros(FA.shape[0], bool) if cap_a is None else np.asarray(cap_a, bool).copy()
    if capA.shape != (FA.shape[0],):
        raise InputError(f"cap_a must have shape ({FA.shape[0]},), got {capA.shape}")
    shifted = False
    if align:
        VA, VB, same, shifted = _aligned(VA, FA, VB, FB, fixA, domain, max_shift, same_tol,
                                         match_tol, match_fraction)
    elif corresponding_only:
        shifted = _aligned(VA, FA, VB, FB, fixA, domain, max_shift, same_tol, match_tol,
                           match_fraction, move=False)[3]
    if corresponding_only and not shifted:
        return _same_a(VA, FA, fixA, capA, "dropped",
                       "B is not a copy of A (shift too large, or the surfaces do not "
                       "coincide where they overlap)")
    if align and same:
        return _same_a(VA, FA, fixA, capA, "absorbed", "corresponding elements coincide")
    out_b = _outside_domain(VB, domain)

    def keep_a(status, reason=""):
        return _same_a(VA, FA, fixA, capA, status, reason)

    lo = np.maximum(VA.min(0), VB.min(0))
    hi = np.minimum(VA.max(0), VB.max(0))
    if (lo > hi).any():
        return _separate(VA, FA, fixA, capA, VB, FB, out_b)
    diag = float(np.linalg.norm(np.r_[VA, VB].max(0) - np.r_[VA, VB].min(0)))
    eps = 1e-5 * diag
    NA = igl.per_vertex_normals(VA, FA)
    NB = igl.per_vertex_normals(VB, FB)
    cov_a = _covered(VA, FA, NA, VB, FB, +1.0, eps)
    cov_b = _covered(VB, FB, NB, VA, FA, -1.0, eps)
    if not cov_a.any() and not cov_b.any():
        both_V = np.r_[VA, VB]
        both_F = np.r_[FA, FB + VA.shape[0]]
        if not self_intersecting_pairs(both_V, both_F, max_pairs=1).size:
            return _separate(VA, FA, fixA, capA, VB, FB, out_b)
        return _fallback(VA, FA, fixA, capA, VB, FB, out_b, "touching without covered vertices")
    if cov_b.all():
        return keep_a("absorbed")
    if cov_a.all() and not fixA.any() and not capA.any() and not out_b.any():
        return MergeResult(VB, FB, fixB, "absorbed")
    kept = (_corresponding_cut(VA, FA, VB, FB, NA, NB, fixA, out_b, eps, band_rings,
                                tilt_cost=tilt_cost, crease_cost=crease_cost)
            if shifted else None)
    if kept is None and corresponding_only:
        # the general cut would fuse them into one larger element
        return keep_a("dropped", "corresponding elements without a coinciding overlap to cut in")
    if kept is not None:
        keep_fa, keep_fb = kept
    else:
        dist_a = np.sqrt(ClosestPoints(VB, FB).query(VA)[0])
        dist_b = np.sqrt(ClosestPoints(VA, FA).query(VB)[0])
        # faces crossing the other surface go too, even with no covered vertex:
        # then no kept face of A can cross a kept face of B
        cross = self_intersecting_pairs(np.r_[VA, VB], np.r_[FA, FB + VA.shape[0]])
        cross = cross[(cross[:, 0] < FA.shape[0]) & (cross[:, 1] >= FA.shape[0])]
        sink_a = np.zeros(FA.shape[0], bool)
        sink_a[cross[:, 0]] = True
        sink_b = out_b[FB].any(axis=1)
        sink_b[cross[:, 1] - FA.shape[0]] = True
        keep_fa = _cut(VA, FA, cov_a, dist_a, fixA, sink_a, band_rings)
        keep_fb = _cut(VB, FB, cov_b | out_b, dist_b, fixB, sink_b, band_rings)
    if not keep_fa.any():
        return _fallback(VA, FA, fixA, capA, VB, FB, out_b, "cut removed all of A")
    if not keep_fb.any():
        return keep_a("absorbed")
    Va, Fa, fa = _compact(VA, FA, keep_fa, fixA)
    ca = capA[keep_fa]
    Vb, Fb, fb = _compact(VB, FB, keep_fb, fixB)
    loops_a = boundary_loops(Fa, Va.shape[0])
    loops_b = boundary_loops(Fb, Vb.shape[0])
    if loops_a is None or loops_b is None:
        return _fallback(VA, FA, fixA, capA, VB, FB, out_b, "non-simple cut boundary")
    pairs = pair_loops(loops_a, Va, loops_b, Vb)
    if not pairs:
        return _fallback(VA, FA, fixA, capA, VB, FB, out_b, "cut loops do not pair up")
    labels = np.r_[np.zeros(Fa.shape[0], np.int64), np.ones(Fb.shape[0], np.int64)]
    problem = ""
    if kept is not None and weld:
        Wa, Wb = _toward_midpoints(Va, Fa, fa, Vb, Fb, VA, FA, VB, FB, fixA.any(), zone,
                                   pull_radius, mu)
        welded = _welded(Wa, Fa, loops_a, Wb, Fb, loops_b, pairs, fixA.any(), weld_tol)
        if welded is not None:
            V, F, parent, used = welded
            problem = _stitch_problem(V, F, np.r_[Va, Vb][used], domain)
            if not problem:
                cap = np.r_[ca, np.zeros(Fb.shape[0], bool)][parent]
                jumps = seam_normal_jumps(V, F, labels[parent])
                return _stitched(V, F, np.r_[fa, np.zeros(Wb.shape[0], bool)][used], cap, 0.0,
                                 jumps, True)
    for pull in pulls:
        if pull > 0:
            Wa, Wb = _pull(Va, Fa, fa, loops_a, Vb, Fb, loops_b, pairs, mu, pull_radius, pull)
        else:
            Wa, Wb = Va, Vb
        V = np.r_[Wa, Wb]
        off = Wa.shape[0]
        strips = [strip_between(loops_a[i], Wa[loops_a[i]], loops_b[j] + off, Wb[loops_b[j]])
                  for i, j in pairs]
        F = np.r_[Fa, Fb + off, *strips]
        fixed = np.r_[fa, np.zeros(Wb.shape[0], bool)]
        problem = _stitch_problem(V, F, np.r_[Va, Vb], domain)
        if not problem:
            break
    if problem:
        return _fallback(VA, FA, fixA, capA, VB, FB, out_b, problem)
    gap = max(float(np.linalg.norm(V[loops_a[i]] - closest_on_polyline(
        V[loops_a[i]], V[loops_b[j] + off]), axis=1).max()) for i, j in pairs)
    jumps = seam_normal_jumps(V, F, np.r_[labels, np.full(F.shape[0] - labels.size, 2)])
    cap = np.r_[ca, np.zeros(F.shape[0] - ca.size, bool)]
    return _stitched(V, F, fixed, cap, gap, jumps, kept is not None)


def _stitch_problem(V, F, V_before, domain) -> str:
    """Why a stitched element is not acceptable (empty when it is)."""
    problem = closed_element_ok(V, F)
    if not problem and domain is not None:
        if (_outside_domain(V, domain) & ~_outside_domain(V_before, domain)).any():
            problem = "seam left the domain"
    return problem


def _stitched(V, F, fixed, cap, gap, jumps, corresponding) -> MergeResult:
    return MergeResult(V, F, fixed, "stitched", seam_gap=gap,
                       seam_normal_jump=float(jumps.max()) if jumps.size else float("nan"),
                       seam_normal_jump_mean=float(jumps.mean()) if jumps.size else float("nan"),
                       seam_edges=int(jumps.size), corresponding=corresponding, cap=cap)


def _toward_midpoints(Va, Fa, fa, Vb, Fb, VA, FA, VB, FB, a_held, zone, radius, mu):
    """Laplacian editing of both kept pieces toward the midpoints of corresponding points.

    The paper's eqs. 6-7 on the overlap zone: every vertex of a piece closer
    than ``zone`` mean edge lengths to the other (whole, aligned) element
    corresponds to its closest point there and is pulled toward the midpoint
    of the two (soft constraint, weight ``mu``; only where the two surfaces
    face the same way within 30 degrees, so that an end cap of one element
    inside the other does not dent it); vertices farther than
    ``radius`` mean edge lengths from the zone, and fixed vertices, are
    held.  When ``A`` is held (it has fixed vertices: a tile frame), ``A``
    stays and ``B`` goes all the way onto it.
    """
    h = 0.5 * ((mean_edge_length(VA, FA, per_face=True) or 1.0)
               + (mean_edge_length(VB, FB, per_face=True) or 1.0))
    out = []
    for V, F, fix, Vo, Fo, share in ((Va, Fa, fa, VB, FB, 0.0 if a_held else 0.5),
                                     (Vb, Fb, None, VA, FA, 1.0 if a_held else 0.5)):
        if share == 0.0:
            out.append(V)
            continue
        d2, fo, C = ClosestPoints(Vo, Fo).query(V)
        # corresponding points: near, and on a part of the other surface facing
        # the same way (not its end cap inside this piece)
        agree = np.einsum("ij,ij->i", igl.per_vertex_normals(V, F), face_normals(Vo, Fo)[fo])
        idx = np.flatnonzero((np.sqrt(d2) < zone * h) & (agree > np.cos(np.radians(30.0))))
        if idx.size == 0:
            out.append(V)
            continue
        held = cKDTree(V[idx]).query(V)[0] > radius * h
        if fix is not None:
            held |= fix
        out.append(laplacian_deformed(V, F, (idx, V[idx] + share * (C[idx] - V[idx])), mu=mu,
                                      fixed=held, laplacian="uniform"))
    return out[0], out[1]


def _welded(Wa, Fa, loops_a, Wb, Fb, loops_b, pairs, a_held, weld_tol):
    """Zip the paired loops of the two pieces into shared seams (no strip, no gap).

    Each loop vertex moves to the midpoint between itself and its
    corresponding point on the partner loop (``B``'s all the way onto
    ``A``'s when ``A`` is held), the point at the same arc-length parameter
    once the loops are lined up (:func:`geotex.quilting.seam.matched_on_loops`;
    at the pointed ends of a flat cross-section the closest point slides
    along the partner, the vertices there do not meet and their fans
    fold), then
    :func:`geotex.quilting.seam.zip_loops` interleaves the two loops.
    Loop vertices that meet a vertex of the other loop (closer than
    ``weld_tol`` of the loop edges) become one vertex.  Returns
    ``(V, F, parent, kept)`` (``parent`` indexes the faces of ``Fa`` then
    ``Fb``, ``kept`` the vertices of ``Wa`` then ``Wb`` still used) or
    ``None``.
    """
    off = Wa.shape[0]
    V = np.r_[Wa, Wb]
    F = np.r_[Fa, Fb + off]
    W = V.copy()
    for i, j in pairs:
        a, b = loops_a[i], loops_b[j] + off
        Pa, Pb = V[a], V[b]
        matched = matched_on_loops(Pa, Pb)
        if matched is None:
            return None
        Qa, Qb = matched
        if not a_held:
            W[a] = Pa + 0.5 * (Qa - Pa)
        W[b] = Pb + (1.0 if a_held else 0.5) * (Qb - Pb)
    parent = np.arange(F.shape[0])
    gone = np.zeros(W.shape[0], bool)
    for i, j in pairs:
        a, b = loops_a[i], loops_b[j] + off
        z = zip_loops(F, a, W[a], b, W[b], weld=weld_tol)
        if z is None:
            return None
        F, p, rep = z
        parent = parent[p]
        if rep:
            vb, va = np.array(list(rep)), np.array(list(rep.values()))
            if not a_held:
                W[va] = 0.5 * (W[va] + W[vb])
            gone[vb] = True
    if gone.any():
        remap = np.cumsum(~gone) - 1
        W, F = W[~gone], remap[F]
    return W, F, parent, ~gone


def _aligned(VA, FA, VB, FB, fixA, domain, max_shift, same_tol, match_tol, match_fraction,
             move=True):
    """Translate A and B toward each other and test whether they are one element.

    Returns ``(VA, VB, same, corresponding)``.  The translation is found by ICP
    of the vertices of ``B`` that lie over the overlap of the two footprints
    (so that a strand overlapping another strand's end is not slid along
    it).  The pair corresponds when the shift is at most ``max_shift`` of
    ``B``'s narrow width (position) and, after the shift, the two surfaces
    coincide over their common box on both sides (shape,
    :func:`_coincide_where_overlapping`).  With ``move=False`` nothing moves
    and only the shape test is made, as the pair stands.
    """
    target = ClosestPoints(VA, FA)
    ext = VB.max(0)[:2] - VB.min(0)[:2]
    foot, narrow = float(ext.mean()), float(ext.min())
    lo = np.maximum(VA.min(0), VB.min(0))[:2]
    hi = np.minimum(VA.max(0), VB.max(0))[:2]
    sel = ((VB[:, :2] >= lo) & (VB[:, :2] <= hi)).all(axis=1)
    if sel.sum() < 3:
        return VA, VB, False, False
    if not move:
        ok = _coincide_where_overlapping(target, VA, VB, FB, domain, match_tol * narrow,
                                         match_fraction)
        return VA, VB, False, ok
    s, info = icp_translation(VB[sel], target=target, free=(True, True, False),
                              max_iterations=30, tol=1e-6 * foot, method="plane")
    if not (np.linalg.norm(s) <= max_shift * narrow and info.rms <= match_tol * narrow):
        return VA, VB, False, False
    if not _coincide_where_overlapping(target, VA, VB + s, FB, domain, match_tol * narrow,
                                       match_fraction):
        return VA, VB, False, False
    alpha = 0.0 if fixA.any() else 0.5
    VA2 = VA - alpha * s if alpha else VA
    VB2 = VB + (1.0 - alpha) * s
    # B adds nothing to A: B lies on A (its part outside the domain aside: a
    # frame half is the copy's element cut at the tile side)
    inside = ~_outside_domain(VB2, domain)
    same = bool(inside.any()
                and target.query(VB[inside] + s)[0].mean() < (same_tol * foot) ** 2)
    return VA2, VB2, same, True


def _coincide_where_overlapping(target_a, VA, VB, FB, domain, tol, fraction) -> bool:
    """True when A and B (already aligned) are the same element where both exist.

    The shape test of the correspondence: over the common box of the two
    footprints (grown by ``tol``, inside the domain), at least ``fraction``
    of ``A``'s vertices lie within ``tol`` of ``B``'s surface or inside
    ``B``, *and* at least ``fraction`` of ``B``'s on or inside ``A``.  Two
    copies of one element, or a frame half and the copy of its element
    (whose part beyond the tile side is outside the domain), pass with
    nearly all vertices; pieces of one strand overlapping end to end pass
    with their end caps inside each other (measured 0.88-0.98 on the
    strands joined in the weave quilts of ``benchmarks/bench_seams.py``).
    A jittered scale whose tip ends a tenth of its width beyond the frame
    half it was aligned to scores 0.78 (``scales-planar``): a neighbour of
    similar shape, not the same element.
    """
    lo = np.maximum(VA.min(0), VB.min(0))[:2] - tol
    hi = np.minimum(VA.max(0), VB.max(0))[:2] + tol
    if domain is not None:
        lo = np.maximum(lo, np.asarray(domain[:2], dtype=np.float64))
        hi = np.minimum(hi, np.asarray(domain[2:], dtype=np.float64))
    in_a = ((VA[:, :2] >= lo) & (VA[:, :2] <= hi)).all(axis=1)
    in_b = ((VB[:, :2] >= lo) & (VB[:, :2] <= hi)).all(axis=1)
    if in_a.sum() < 3 or in_b.sum() < 3:
        return False
    # a vertex inside the other element counts as matched: the end cap of a
    # strand piece inside the strand it continues
    on_a = ((ClosestPoints(VB, FB).query(VA[in_a])[0] <= tol * tol)
            | (igl.winding_number(VB, FB, VA[in_a]) > 0.5))
    on_b = ((target_a.query(VB[in_b])[0] <= tol * tol)
            | (igl.winding_number(target_a.V, target_a.F, VB[in_b]) > 0.5))
    return bool(on_a.mean() >= fraction and on_b.mean() >= fraction)


def _separate(VA, FA, fixA, capA, VB, FB, out_b):
    if out_b.any():
        return _same_a(VA, FA, fixA, capA, "dropped", "B leaves the domain")
    return MergeResult(np.r_[VA, VB], np.r_[FA, FB + VA.shape[0]],
                       np.r_[fixA, np.zeros(VB.shape[0], bool)], "separate", parts=2,
                       cap=np.r_[capA, np.zeros(FB.shape[0], bool)])


def _pull(Va, Fa, fa, loops_a, Vb, Fb, loops_b, pairs, mu, radius, strength):
    """Laplacian-deform both pieces so that paired loops meet half way."""
    out = []
    for V, F, fix, loops, Vo, loops_o, side in ((Va, Fa, fa, loops_a, Vb, loops_b, 0),
                                                  (Vb, Fb, None, loops_b, Va, loops_a, 1)):
        idx, tgt = [], []
        for pair in pairs:
            mine, other = (pair[0], pair[1]) if side == 0 else (pair[1], pair[0])
            P = V[loops[mine]]
            C = closest_on_polyline(P, Vo[loops_o[other]])
            idx.append(loops[mine])
            tgt.append(P + 0.5 * strength * (C - P))
        idx = np.concatenate(idx)
        tgt = np.concatenate(tgt)
        edges = np.r_[F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]]
        h = float(np.linalg.norm(V[edges[:, 0]] - V[edges[:, 1]], axis=1).mean()) or 1.0
        far = cKDTree(V[idx]).query(V)[0] > radius * h
        fixed = far if fix is None else (far | fix)
        out.append(laplacian_deformed(V, F, (idx, tgt), mu=mu, fixed=fixed,
                                      laplacian="uniform"))
    return out[0], out[1]


def _fallback(VA, FA, fixA, capA, VB, FB, out_b, reason):
    if out_b.any():
        return _same_a(VA, FA, fixA, capA, "dropped", reason + "; B leaves the domain")
    solid = manifold_of(VA, FA) + manifold_of(VB, FB)
    if solid.status().name != "NoError" or solid.is_empty():
        return _same_a(VA, FA, fixA, capA, "dropped", reason + "; union failed")
    V, F = arrays_of_manifold(solid)
    fixed = np.zeros(V.shape[0], bool)
    if fixA.any():
        want = np.unique(VA[fixA], axis=0)
        both = np.r_[want, V]
        _, inv = np.unique(both, axis=0, return_inverse=True)
        inv = inv.ravel()
        fixed = np.isin(inv[want.shape[0]:], inv[:want.shape[0]])
        if np.unique(inv[want.shape[0]:][fixed]).size < want.shape[0]:
            return _same_a(VA, FA, fixA, capA, "dropped",
                           reason + "; union would move fixed vertices")
    if closed_element_ok(V, F, intersections=False):
        return _same_a(VA, FA, fixA, capA, "dropped", reason + "; union not closed")
    cap = np.zeros(F.shape[0], bool)
    if capA.any():
        cap = caps_like(V, F, VA, FA[capA])
        if cap is None:
            return _same_a(VA, FA, fixA, capA, "dropped", reason + "; union lost the caps")
    return MergeResult(V, F, fixed, "union", reason=reason, cap=cap)
