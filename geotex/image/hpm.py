"""Hierarchical pattern mapping (Soler, Cani, Angelidis 2002): texture coordinates into one image.

The surface is covered coarse to fine by patches cut from the input image
itself: no new texture is made, the output is per-corner texture coordinates
into the original image.

1. A top-down face-cluster hierarchy (:mod:`geotex.patches.clusters`) and its
   barycentric coordinates (:mod:`geotex.patches.flatten`) are built once.
2. The first patch is the flattest cluster of the coarsest level that has a
   cluster flat enough (flattening error ``|area ratio - 1|`` below
   ``max_flat_error``) and fits in the image; it goes at a random position,
   oriented by ``angle`` (or a random angle, or the direction field).
3. Levels are drained coarse to fine.  In a level, the cluster with the
   largest share of its border next to textured faces goes first (the
   paper's priority).  A cluster is flattened through its control polygon;
   if it is not a disc, too distorted, or larger than the image, its
   children go to the next level.  Otherwise a band of the textured faces
   along it is drawn in its frame with the colours these faces already
   show: the mask.  The band is either the paper's (``band_mode=
   "topological"``: the faces of each textured neighbour cluster whose
   topological position value w.r.t. the shared control-polygon edges is
   below ``band``, §4.1) or, by default, the textured faces within
   ``band_distance * scale`` of the cluster along mesh edges (a band of
   constant surface width; on Spot with gravel it gave a border/within
   colour contrast of 1.45 against 1.67 for the topological band at the
   same cost: the topological band is one face thin along small clusters
   and very wide along large ones).  The best position and orientation of the
   mask in the image (FFT correlation, :mod:`geotex.image.fftmatch`, over
   ``orientations`` angles) gives the cluster's texture coordinates; if the
   relative error (mean squared colour difference per mask pixel divided by
   twice the image's colour variance: 1 is as bad as random pixels) exceeds
   ``max_error`` the cluster is subdivided instead.  Besides the FFT
   candidates (``orientations`` discrete angles), the rigid placement that
   continues the main neighbour's own texture coordinates (least-squares fit
   on the band vertices of the neighbouring placement that holds most of
   them, any angle) is tried and kept when its error is lower and it stays
   inside the image.  Its rotation is that neighbour's orientation in the
   cluster's frame: the FFT search keeps only the orientations within
   ``orientation_spread`` of it, so that the orientation propagates from
   the first patch as in the paper (with every orientation free, a thin
   band of a structured texture such as bricks was matched as well by a
   patch turned by 90 or 180 degrees, and rows changed direction at most
   patch borders).
   On the finest cluster level (a few faces per cluster, see
   :func:`geotex.patches.clusters.cluster_hierarchy`) a cluster that cannot
   be flattened is not dropped to single faces: if its barycentric
   flattening folds (its vertices take coordinates from different base
   triangles of a polygon laid out with 3D lengths) it is flattened by
   projection onto its mean plane (if that is within ``max_flat_error``),
   and if imposing the neighbours' border folds it, its free flattening is
   kept.  A match above ``max_error`` is still refused there (for a stochastic
   sample; a periodic one keeps it when its faces are smaller than
   ``min_patch`` periods, see "Structured patterns" below): the face
   level (5) retries its faces in smaller groups, with more of their
   neighbours textured (forcing such patches above the threshold had given
   a mean colour jump of 0.17 at their borders on Spot, against 0.06-0.10
   for faces unfolded from their neighbours).  The report counts, per level, why clusters were
   refused (``refused``) and the two fallbacks (``projected``,
   ``free_border``).
4. Cracks: a vertex reached through several faces gets the mean of its
   values (in-cluster cracks); the vertices the cluster shares with textured
   faces take the positions the neighbours' band has in the cluster's frame,
   imposed during the recursive traversal (border cracks); after placement,
   a shared border vertex whose coordinates come within ``snap`` pixels of
   the neighbour's takes the neighbour's exactly (no seam, no vertex split).
   Then the local edge relaxation of the paper's Fig. 6 moves the cluster's
   border vertices in texture space, by a greedy random search in a disc
   that shrinks at each of three rounds, to reduce the colour difference
   along the shared edges (weighted by the hat function of the vertex); the
   moves are spread inside the cluster by running the barycentric recursion
   again with the moved vertices imposed (the paper's pink region).
5. At the face level (``face_match``, default), the faces still without
   texture (clusters of the finest level that matched badly or could not be
   flattened) are cut into groups of at most ``face_group`` adjacent faces
   (runs of the breadth-first order of each connected gap; by default 4
   without a field, single faces with one).  Each group is
   flattened by projection onto its mean plane and matched like a cluster
   (the constant-width band, the FFT search, the continuation of *every*
   textured neighbour placement as a candidate, not only the main one; the
   same threshold), in the order of the share of its border that is
   textured; a group that fails is retried face by face, and only a face
   that still matches worse than ``max_error`` (or cannot be flattened) is
   unfolded from a textured neighbour across an edge (the neighbour's
   linear map extended over the face unfolded about the shared edge).  The
   report gives ``matched_faces`` and, as ``filled_faces``, the unfolded
   ones.  On Spot (10k faces, seeds 0-2) the colour jump where the map is
   discontinuous fell from 0.220 / 0.105 / 0.115 (gravel / bricks / water,
   every remaining face unfolded) to 0.203 / 0.094 / 0.107, with 0-42
   faces of 10k left to unfold instead of 356-834.
   With a field (structured samples, see below), a face-level fit first
   scores the neighbours' continuations (turned onto the field, without
   lattice moves) by their band error, with the bilinear lookups; when one is
   under ``max_error`` and keeps the faces inside the image, the lowest is
   taken without the FFT search (the report counts them as ``quick``).  This
   differs from the full search in two ways: the FFT minimum, which can be
   lower, is not looked for (the paper's rule takes the best match under the
   threshold; a continuation under it is a match under the threshold, and
   the seamless one), and the continuation keeps its position instead of
   moving to the FFT minimum within ``CONTINUATION_WINDOW`` of it (the phase
   correction below); without a field the order is unchanged (stochastic
   samples: byte-identical).  On Spot 10k (seed 0) 588 / 620 of the ~3000
   face-level fits of slate tiles / rough metal pass this way (~43 % of the
   single faces that pass, two thirds of the groups): FFT searches 2975 ->
   2299 and 2732 -> 2010, CPU -5 to -10 %, faces left to unfold 1140 -> 1112
   and 865 -> 804; over seeds 0-2 the seams (patch borders, where the map
   jumps), stretch and rotation across borders stayed within the seed spread
   (benchmarks/results/hpm_images.md, h-hpm10).
   A face-level fit is mostly of one triangle, so what depends on the mesh
   alone is computed once per mapping (every face's field coefficients, the
   mean-plane frames of every group and of each of its faces alone, the faces
   across each cluster's and group's border for the priorities), the band
   search and the relaxation's error are compiled
   (:mod:`geotex.image.hpm_faces`, ``_relax_error_compiled``) and the mask
   planes are kept between fits: the same uv bit for bit, CPU -23 to -33 % on
   slate tiles and -26 to -32 % on rough metal (Spot 10k, seeds 0-2; face
   level -27 / -31 %), -13 to -21 % on bricks, gravel and water
   (benchmarks/results/hpm_images.md, h-hpm11).

Structured patterns (``structure``, §5.1-5.2 of the paper).  The sample's
pattern period and anisotropy are estimated once
(:func:`geotex.image.fftmatch.pattern_scale`: the repeats of its
autocorrelation and the coherence of its structure tensor).  A periodic
sample (bricks, weaves, nets, tiles) gets a fitting band of at least half a
period, its neighbours' continuations moved by whole periods as candidates
(kept whenever below ``max_error``) and no split of a cluster whose
children are smaller than ``min_patch`` periods (its best match is kept
above the threshold); an anisotropic one (coherence > 0.3) a band
``1 + coherence`` wider, as the paper advises.  Stochastic samples are not
affected.  See :func:`hpm_texture` for the measured effect of each.

Lattice snapping (periodic samples, part of the border cracks of 4): after
the exact snapping, a shared border vertex whose position lies within
``LATTICE_SNAP`` (0.12) of the shortest period of a copy of the
neighbour's position moved by whole periods (for stripes: whose phase
across the stripes differs by less than that) takes that copy, unless it
folds a face; the moves are spread inside the cluster by the recursive
mapping like the relaxation's, and the relaxation then works on the other
border vertices.  The map still jumps there (by a lattice vector), but the
pattern keeps its phase and orientation across the border: where two
chains of continuations meet, the mismatch of a third of a cell that
remained is removed where it is small (on Bob with the basket weave the
distance of the jumps to the lattice, quartiles in periods, went from
0.03 / 0.14 / 0.31 to 0.01 / 0.11 / 0.28: most of the mismatch is too
large to snap without folding faces).  See :func:`hpm_texture`
(``structure``) for what it changed.

One orientation over the surface (``orientation_field``, issue 16; paper
§5.1, Fig. 10).  Propagating the neighbour's orientation from patch to patch
(the paper's way) lets it drift with the surface's curvature: regions grown
separately meet turned (on Spot 10k with bricks, basket weave and rope net a
quarter of the patch-border edges turned by 25-35 degrees or more).  For a
periodic or anisotropic sample the orientation therefore comes, by default,
from the smoothest line field of the surface
(:func:`geotex.fields.smooth_direction_field`, a cross field for a sample
that looks the same after a quarter turn; combed so that separately started
regions agree on its sign), as for a user's ``field``: a cluster's direction
is the area-weighted ``N``-fold mean of the field carried into its
flattening by every face's linear map; a cluster over which it is not
coherent enough for one rigid patch (``FIELD_COHERENCE``) is subdivided;
the FFT search uses that one orientation (the grid turned onto it); the
neighbours' continuations (and their whole-period moves) are turned onto it
about their shared border when they need at most ``field_tolerance`` and
then moved to the lowest matching error within ``CONTINUATION_WINDOW`` of a
pattern size (their phase is corrected, the orientation kept; every
continuation and every whole-period move is so moved, on the FFT energies
already computed, and the lowest is the candidate: before, the moves were
ranked by bilinear band errors, a tenth of the CPU time on bricks), so a cluster
whose FFT minimum is above ``max_error`` is refused before its continuations
are evaluated (their lattice moves were a quarter of the CPU time on slate
tiles, where most face-level fits fail; before, a continuation whose window
held no admissible position kept its bilinear error and could pass: 29 of
about 1700 refusals on Spot 10k with slate tiles); crack moves
(lattice snapping, relaxation) that turn the patch by more than
``FIELD_SNAP_TURN`` / ``FIELD_MOVE_TURN`` degrees are undone.  The pattern
then breaks only at the field's singularities and the combing's cut, and
where two neighbours' phases disagree.  See :func:`hpm_texture`
(``orientation_field``) for what it changed.

Sub-pixel refinement (``subpixel``, off by default): the FFT minimum lies
on whole matching pixels and on the orientation grid; with ``subpixel`` it
is refined by parabolas of the continuous mask error (bilinear samples) in
x, y (half-pixel steps) and the angle (steps of half the grid, about the
mask's centroid), two rounds, and the candidates are compared by that error.
Measured on Spot (10k, seeds 0-2) it did not help the seams: the
border/within contrast went from 1.54 / 1.34 to 1.57 / 1.36 (gravel /
bricks), because the refined matches now beat the exact continuation of the
main neighbour (chosen 257 -> 39 times on bricks with face matching), whose
borders are seamless after snapping; refining x and y only gave 1.52 / 1.36
(within the seed-to-seed spread of about 0.03).

Differences from the paper, besides the face level (the paper gives no detail):
the topological coordinates of inner vertices use the three nearest parent
corners (see :class:`geotex.patches.flatten.BarycentricHierarchy`); the mask is
rasterized on the CPU at a matching resolution of at most ``match_size`` pixels
(the image is block-averaged to it) instead of rendered by graphics hardware;
the colour space is an opponent space instead of HSV (see
:mod:`geotex.image.fftmatch`); the flattening uses mean value coordinates over
the parent polygon instead of the paper's three-corner stable base, which folds
faces where the chosen corners change (``flattening``, see
:func:`geotex.patches.flatten.barycentric_hierarchy`); the mask is drawn in a
frame turned so that the main neighbour's orientation is one of the searched
orientations, and its exact continuation is a candidate (the paper draws the
mask at a random orientation to avoid such trivial solutions).
"""

from __future__ import annotations

import heapq
from dataclasses import dataclass, field

import numpy as np
from PIL import Image
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components, dijkstra

from geotex.errors import InputError, MissingFileError
from geotex.image.atlas import rasterize_triangles
from geotex.jit import JIT_MIN_SIZE, compiled, helper
from geotex.fields.combing import comb_direction_field
from geotex.fields.directions import smooth_direction_field
from geotex.image.fftmatch import (match_energy, opponent_colors, pattern_scale,
                                   quarter_turn_symmetry, texture_spectra)
from geotex.image.hpm_faces import field_coefficients, textured_band, vertex_faces
from geotex.image.patches import load_image
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.geometry import degenerate_faces, face_areas
from geotex.mesh.record import Mesh
from geotex.mesh.topology import edge_topology
from geotex.options import count, finite_number, positive_number
from geotex.patches.clusters import cluster_hierarchy
from geotex.patches.flatten import (barycentric_hierarchy, cluster_frames, control_polygon,
                                    edge_band, flatten_cluster, polygon_coordinates)
from geotex.patches.grow import face_adjacency
from geotex.progress import report

#: Structure-tensor coherence above which a sample counts as anisotropic and the fitting
#: band is widened by ``1 + coherence`` (see :func:`hpm_texture`).
ANISOTROPIC_COHERENCE = 0.3
#: Width of the fitting band of a periodic sample, as a fraction of its period.
PATTERN_BAND = 0.5

#: Lattice moves of a neighbour's continuation tried per fit (periodic samples).
LATTICE_CANDIDATES = 24

#: A border vertex of a periodic sample within this fraction of the shortest period of a
#: lattice copy of its neighbour's texture position takes that copy (see :func:`hpm_texture`).
LATTICE_SNAP = 0.12

#: Smallest coherence of the field over a cluster (``|mean exp(i N phi)|``, see
#: ``field_direction`` in :func:`hpm_texture`) for one rigid patch; a cluster where the
#: field turns more is subdivided (not on the finest cluster level).
FIELD_COHERENCE = 0.95

#: With a field, a neighbour's continuation is moved to the lowest matching error within
#: this fraction of the pattern size (period, or correlation length) of it.
CONTINUATION_WINDOW = 0.25

#: With a field, crack moves (lattice snapping, relaxation) spread inside a patch are undone
#: when they turn it by more than this many degrees.
FIELD_MOVE_TURN = 1.0

#: The same for the lattice snapping (it keeps the pattern's phase across borders).
FIELD_SNAP_TURN = 3.0

#: Quarter-turn symmetry of a sample's autocorrelation from which its field is a cross
#: field (4 directions) instead of a line field.
QUARTER_TURN = 0.8

#: Bases from this many faces up sample the image, rasterize the masks and assemble
#: the matching energies with compiled loops (the same values; ``GEOTEX_JIT_MIN_SIZE``
#: lower than this lowers it).  A mapping of 2000 faces does tens of thousands of
#: lookups; below that, loading numba (~0.4 s once) costs more.
SAMPLE_JIT_FACES = 2000

#: Multiplier that mirrors 2D positions (k, 2) in y: ``P * FLIP_Y`` is ``(x, -y)`` exactly.
FLIP_Y = np.array([1.0, -1.0])

#: Largest relaxation move, as a fraction of the shortest edge at the vertex (texture space).
RELAX_EDGE_FRACTION = 0.2

__all__ = ["HPMLevel", "HPMResult", "hpm_texture", "check_hpm_base", "read_hpm_image",
           "hpm_mesh"]


@dataclass
class HPMLevel:
    """What happened on one level of the hierarchy."""

    level: int
    clusters: int
    placed: int = 0
    subdivided: int = 0
    errors: list = field(default_factory=list)
    filled_faces: int = 0
    continued: int = 0
    refused: dict = field(default_factory=dict)
    projected: int = 0
    free_border: int = 0
    matched_faces: int = 0
    forced: int = 0
    lattice_snapped: int = 0
    field_refused: int = 0
    quick: int = 0

    @property
    def mean_error(self) -> float:
        """Mean relative matching error of the placed clusters (nan if none)."""
        return float(np.mean(self.errors)) if self.errors else float("nan")

    def as_dict(self) -> dict:
        """JSON-ready summary."""
        return {"level": self.level, "clusters": self.clusters, "placed": self.placed,
                "subdivided": self.subdivided,
                "mean_error": None if not self.errors else self.mean_error,
                "filled_faces": self.filled_faces, "continued": self.continued,
                "refused": dict(sorted(self.refused.items())), "projected": self.projected,
                "free_border": self.free_border, "matched_faces": self.matched_faces,
                "forced": self.forced, "lattice_snapped": self.lattice_snapped,
                "field_refused": self.field_refused, "quick": self.quick}


@dataclass(frozen=True, eq=False)
class HPMResult:
    """Texture coordinates of a hierarchical pattern mapping.

    Attributes
    ----------
    uv : numpy.ndarray, (k, 2) float64
        Texture coordinates into the input image (``u`` right, ``v`` up,
        ``[0, 1]`` over the image).
    uv_faces : numpy.ndarray, (m, 3) int64
        Per-corner indices into ``uv``; a vertex has several uv only where
        the mapping jumps.
    patch : numpy.ndarray, (m,) int64
        Placement that textured every face (``-1``: filled at face level).
    face_level : numpy.ndarray, (m,) int64
        Hierarchy level of that placement (the last level for filled faces).
    levels : list of HPMLevel
    pattern : dict
        The sample's pattern estimate and what was derived from it
        (:func:`geotex.image.fftmatch.pattern_scale`): ``periodic``,
        ``period_px``, ``correlation_length_px``, ``coherence``,
        ``min_patch`` (surface units, 0 when not used), ``band_width``
        (surface units) and, for a periodic sample, ``patch_periods``: the
        area-weighted median equivalent-disc diameter of the placements, in
        pattern periods (below 1 the patches are smaller than the pattern,
        whose structure may then break at their borders, paper §5.2:
        Fertility with the rope net 0.93 at 0.3 x its diagonal, where the
        net is broken, 1.27 at 0.15, where it reads as a net; Bob with the
        basket weave 1.11 at 0.35, 1.37 at 0.2; Spot (23k faces) with
        bricks 0.87 at 0.35, where the rows still read as rows).
    """

    uv: np.ndarray
    uv_faces: np.ndarray
    patch: np.ndarray
    face_level: np.ndarray
    levels: list
    pattern: dict = field(default_factory=dict)

    def report(self) -> dict:
        """Per-level counts and mean matching errors, JSON-ready."""
        return {"levels": [lv.as_dict() for lv in self.levels],
                "placements": int(self.patch.max() + 1) if self.patch.size else 0,
                "vertices_split": int(self.uv.shape[0]), "pattern": dict(self.pattern)}


def check_hpm_base(V, F) -> None:
    """Refuse a base that is not closed, edge-manifold and consistently oriented.

    Several closed parts are accepted (each is started at a random position
    of the image when it has no textured neighbour).

    Raises
    ------
    InputError
        Naming what is wrong (open, non-manifold, badly oriented).
    """
    topo = edge_topology(F, V.shape[0])
    if topo.non_manifold.size:
        raise InputError(f"the base mesh is non-manifold ({topo.non_manifold.size} edges with "
                         "more than two faces); repair it first (geotex repair)")
    if topo.boundary.size:
        raise InputError(f"the base mesh is open ({topo.boundary.size} boundary edges); "
                         "hierarchical pattern mapping needs a closed surface: close it "
                         "first (geotex repair)")
    if topo.inconsistent.size:
        raise InputError("the base mesh is not consistently oriented; repair it first "
                         "(geotex repair)")


def _image_arg(image) -> np.ndarray:
    arr = np.asarray(image)
    if arr.ndim == 2:
        arr = np.repeat(arr[:, :, None], 3, axis=2)
    if arr.ndim != 3 or arr.shape[2] not in (3, 4) or min(arr.shape[:2]) < 8:
        raise InputError(f"image must be a grey or RGB(A) picture of at least 8 x 8 pixels, "
                         f"got shape {arr.shape}")
    if arr.dtype != np.uint8:
        raise InputError(f"image must be uint8, got dtype {arr.dtype}")
    return np.ascontiguousarray(arr[:, :, :3])


def _block_mean(img: np.ndarray, f: int) -> np.ndarray:
    if f == 1:
        return img.copy()
    h, w = (img.shape[0] // f) * f, (img.shape[1] // f) * f
    x = img[:h, :w].reshape(h // f, f, w // f, f, img.shape[2])
    return x.mean(axis=(1, 3))


def _sample(img: np.ndarray, xy: np.ndarray, fast: bool = False) -> np.ndarray:
    """Bilinear samples of ``img`` (h, w, c) at pixel positions ``xy`` (x, y), clamped.

    With ``fast`` the compiled loop :func:`_sample_compiled` gives the same
    values bit for bit without the numpy temporaries (positions with a NaN
    keep the numpy path).
    """
    h, w = img.shape[:2]
    if fast and h > 1 and w > 1 and not np.isnan(xy).any():
        return _sample_compiled(img, np.ascontiguousarray(xy, dtype=np.float64))
    x = np.clip(xy[:, 0] - 0.5, 0.0, w - 1.0)
    y = np.clip(xy[:, 1] - 0.5, 0.0, h - 1.0)
    x0 = np.minimum(np.floor(x).astype(np.int64), w - 2) if w > 1 else np.zeros(x.size, np.int64)
    y0 = np.minimum(np.floor(y).astype(np.int64), h - 2) if h > 1 else np.zeros(y.size, np.int64)
    fx = (x - x0)[:, None]
    fy = (y - y0)[:, None]
    # row gathers from the flattened image (np.take: cheaper than 2-d fancy indexing,
    # the same values)
    flat = img.reshape(h * w, -1)
    i00 = y0 * w + x0
    dx = np.minimum(x0 + 1, w - 1) - x0
    dy = (np.minimum(y0 + 1, h - 1) - y0) * w
    top = np.take(flat, i00, axis=0) * (1 - fx) + np.take(flat, i00 + dx, axis=0) * fx
    bot = np.take(flat, i00 + dy, axis=0) * (1 - fx) + np.take(flat, i00 + dy + dx, axis=0) * fx
    return top * (1 - fy) + bot * fy


@helper
def _bilinear(img, px, py, out, i):
    """Row ``i`` of ``out``: the bilinear sample of ``img`` at ``(px, py)``, as
    :func:`_sample` computes it (image of at least 2 x 2 pixels, no NaN)."""
    h, w, nc = img.shape
    x = min(max(px - 0.5, 0.0), w - 1.0)
    y = min(max(py - 0.5, 0.0), h - 1.0)
    x0 = min(int(np.floor(x)), w - 2)
    y0 = min(int(np.floor(y)), h - 2)
    fx = x - x0
    fy = y - y0
    x1 = min(x0 + 1, w - 1)
    y1 = min(y0 + 1, h - 1)
    for k in range(nc):
        top = img[y0, x0, k] * (1 - fx) + img[y0, x1, k] * fx
        bot = img[y1, x0, k] * (1 - fx) + img[y1, x1, k] * fx
        out[i, k] = top * (1 - fy) + bot * fy


@compiled
def _sample_compiled(img, xy):
    """:func:`_sample` for an image of at least 2 x 2 pixels and positions without NaN:
    the same operations in the same order per sample, so the same values."""
    n = xy.shape[0]
    out = np.empty((n, img.shape[2]))
    for i in range(n):
        _bilinear(img, xy[i, 0], xy[i, 1], out, i)
    return out


@compiled
def _relax_error_compiled(full, cand, owner, b, target, ts, nv):
    """The error of :func:`_relax` per movable vertex (its ``err``) without temporaries:
    per sample along each shared edge the numpy path's operations in its order (the
    colour sum in channel order, as ``np.sum`` over fewer than 8 channels), accumulated
    per vertex in row order as ``np.bincount``: the same values."""
    out = np.zeros(nv)
    _relax_error_into(full, cand, owner, b, target, ts, out)
    return out


@compiled
def _relax_search_compiled(full, cur, off, owner, b, target, ts, e0):
    """:func:`_relax`'s greedy search: for each offset block ``off[i]`` (k, 2) in turn,
    the candidates ``cur + off[i]``, their errors (:func:`_relax_error_compiled`'s
    values) and the moves of the vertices whose error falls, as the numpy loop does.
    Returns the new positions (k, 2)."""
    cur = cur.copy()
    e0 = e0.copy()
    n = cur.shape[0]
    e1 = np.zeros(n)
    cand = np.empty_like(cur)
    for i in range(off.shape[0]):
        for v in range(n):
            cand[v, 0] = cur[v, 0] + off[i, v, 0]
            cand[v, 1] = cur[v, 1] + off[i, v, 1]
            e1[v] = 0.0
        _relax_error_into(full, cand, owner, b, target, ts, e1)
        for v in range(n):
            if e1[v] < e0[v]:
                cur[v, 0] = cand[v, 0]
                cur[v, 1] = cand[v, 1]
                e0[v] = e1[v]
    return cur


@helper
def _relax_error_into(full, cand, owner, b, target, ts, out):
    """Body of :func:`_relax_error_compiled`: adds the errors to ``out`` (zeros)."""
    nt = ts.size
    s = np.empty((1, full.shape[2]))
    for e in range(owner.size):
        o = owner[e]
        for j in range(nt):
            u = 1 - ts[j]
            _bilinear(full, cand[o, 0] * u + b[e, 0] * ts[j], cand[o, 1] * u + b[e, 1] * ts[j],
                      s, 0)
            r = e * nt + j
            d = s[0, 0] - target[r, 0]
            acc = d * d
            for k in range(1, s.shape[1]):
                d = s[0, k] - target[r, k]
                acc += d * d
            out[o] += acc * u


@compiled
def _window_minima(E, ix, iy, win):
    """Per point ``(ix[i], iy[i])``: the lowest value of ``E`` (h, w) in the window of
    ``win`` pixels around it (clipped to ``E``) and its row and column, the first in
    row-major order among equal values (as ``np.argmin`` of the window); ``inf`` (and
    row, column 0) where the window is empty or holds no finite value."""
    n = ix.size
    h, w = E.shape
    val = np.full(n, np.inf)
    by = np.zeros(n, np.int64)
    bx = np.zeros(n, np.int64)
    for i in range(n):
        for y in range(max(iy[i] - win, 0), min(max(iy[i] + win + 1, 0), h)):
            for x in range(max(ix[i] - win, 0), min(max(ix[i] + win + 1, 0), w)):
                if E[y, x] < val[i]:
                    val[i] = E[y, x]
                    by[i] = y
                    bx[i] = x
    return val, by, bx


class _State:
    """Mutable state of one mapping run (corner texture positions in full-res pixels)."""

    def __init__(self, V, F, m):
        self.corner = np.zeros((m, 3, 2))
        self.done = np.zeros(m, bool)
        self.patch = np.full(m, -1, np.int64)
        self.face_level = np.full(m, -1, np.int64)
        self.n_patch = 0
        n = V.shape[0]
        self.vacc = np.zeros((n, 2))        # sum of textured corner positions per vertex
        self.vcnt = np.zeros(n)             # number of textured corners per vertex
        self.vsq = np.zeros(n)              # sum of squared norms (to detect disagreement)
        self._agreed = None                 # cache of agreed()
        self._dirty = None                  # vertices marked since, whose rows it updates
        self.vpatch = np.full(n, -1, np.int64)  # last placement that textured each vertex

    def _agreed_rows(self, idx):
        c = np.maximum(self.vcnt[idx], 1.0)
        mean = self.vacc[idx] / c[:, None]
        spread = self.vsq[idx] / c - np.sum(mean * mean, axis=1)
        ok = (self.vcnt[idx] > 0) & (spread < 1e-6 * (1.0 + self.vsq[idx] / c))
        return np.where(ok[:, None], mean, np.nan)

    def agreed(self) -> np.ndarray:
        """Per-vertex mean textured position, nan where none or where corners disagree.

        The returned array is read-only and valid until the next :meth:`mark`
        (which updates it in place: do not keep it across one).
        """
        if self._agreed is None:
            self._agreed = self._agreed_rows(slice(None))
        elif self._dirty is not None:
            self._agreed.setflags(write=True)
            self._agreed[self._dirty] = self._agreed_rows(self._dirty)
        self._agreed.setflags(write=False)
        self._dirty = None
        return self._agreed

    def mark(self, F, faces, corner, patch, level):
        """Record the corner positions of newly textured faces."""
        self.corner[faces] = corner
        self.done[faces] = True
        self.patch[faces] = patch
        self.face_level[faces] = level
        cv = F[faces].ravel()
        self._dirty = cv if self._dirty is None else np.concatenate([self._dirty, cv])
        self.vpatch[cv] = patch
        n = self.vcnt.size
        self.vcnt += np.bincount(cv, minlength=n)
        cu = corner.reshape(-1, 2)
        self.vacc[:, 0] += np.bincount(cv, weights=cu[:, 0], minlength=n)
        self.vacc[:, 1] += np.bincount(cv, weights=cu[:, 1], minlength=n)
        self.vsq += np.bincount(cv, weights=np.sum(cu * cu, axis=1), minlength=n)


def hpm_texture(V, F, image, *, scale: float, field=None, angle: float | None = None,
                seed: int | None = 0, orientations: int = 20, max_error: float = 0.35,
                max_flat_error: float = 0.2, band: float = 0.2,
                orientation_spread: float | None = 30.0,
                band_mode: str = "distance", band_distance: float = 0.06,
                match_size: int = 200, flattening: str = "mean_value",
                snap: float = 1.5, relax: bool = True, face_group: int | None = None,
                subpixel: bool = False, face_match: bool = True, structure: bool = True,
                min_patch: float = 0.3, orientation_field: str = "auto",
                field_tolerance: float = 25.0,
                progress=None) -> HPMResult:
    """Texture a closed mesh with patches of one image, coarse to fine (see module docstring).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        One closed, edge-manifold, consistently oriented surface.
    image : array_like, (h, w) or (h, w, 3 or 4) uint8
        The texture sample (alpha ignored).
    scale : float
        Surface length (mesh units, millimetres for prints) covered by the
        image's width.
    field : DirectionField or array_like (m, 3), optional
        Orientation: every patch's image x axis follows the per-face field
        (its direction over the flattened cluster, the representative of an
        N-direction field nearest the main neighbour's orientation; the FFT
        search uses that orientation only, and the neighbours'
        continuations, moved by whole periods for a periodic sample, are
        candidates when within ``field_tolerance`` of it).  A cluster over
        which the field turns too much for one rigid patch (coherence of
        ``exp(i N phi)`` below ``FIELD_COHERENCE``) is subdivided.
    angle : float, optional
        Orientation of the first patch in degrees (without a field;
        default random).  Later patches take the orientation that fits.
        With the automatic field (``orientation_field``) the field is
        turned by ``angle`` about the normals.
    orientation_field : {"auto", "always", "never"}, optional
        Without ``field``: ``"auto"`` (default) computes the smoothest line
        field of the surface (cross field for a sample that looks the same
        after a quarter turn, see :func:`_pattern_field`) for a periodic or
        anisotropic sample (``structure``) and uses it as ``field``, so that
        one orientation holds over the surface and breaks only at the
        field's singularities (the paper propagates the neighbour's
        orientation, which drifts with the surface's curvature and meets
        itself turned where separately grown regions meet); stochastic
        samples keep the neighbours' orientation (byte-identical).
        ``"always"`` uses the field for every sample, ``"never"`` never.
        Spot 10k, seeds 0-2 (benchmarks/results/hpm.md section 7): rotation
        across patch borders, 75th percentile, bricks / basket weave / rope
        net 25-31 -> 15-18 degrees, inner edges turning by more than 20
        degrees 5.3-6.1 % -> 3.2-3.7 %; median 2-3 -> 4-7 degrees (fewer
        exact continuations); seams where the map jumps unchanged within the
        seed spread; 720-940 placements instead of 580-720, CPU +1-2 s
        (slate tiles 28 -> 41 s, 1150 faces unfolded instead of 350).
    field_tolerance : float, optional
        Degrees: with a field, a neighbour's continuation is a candidate
        only when its orientation is within this of the field's direction.
    seed : int, optional
        Seed of every random choice; same inputs and seed give the same uv.
    orientations : int, optional
        Orientations searched by the FFT matching (>= 1; paper: 19).
    max_error : float, optional
        Largest accepted relative matching error; above it a cluster is
        subdivided (on the finest cluster level: left to the face-level
        filling).
    max_flat_error : float, optional
        Largest flattening error ``|surface area / texture area - 1|``.
    orientation_spread : float or None, optional
        Without ``field``: a cluster next to textured faces is matched only
        at the orientations within this many degrees of its main
        neighbour's (the orientation propagates from the first patch, as in
        the paper); ``None`` searches every orientation.  On Spot with
        bricks, the texture rotation across patch borders went from a
        median of 33 degrees (75th percentile 122) with ``None`` to 9 (31).
    band : float, optional
        Band threshold on the topological position value (§4.1; the
        paper's 0.2): the mask holds the faces of each textured neighbour
        cluster whose position value w.r.t. its control-polygon edges along
        the cluster is below it.
    band_mode : {"topological", "distance"}, optional
        ``"distance"``: the mask holds the textured faces within
        ``band_distance * scale`` of the cluster along mesh edges instead
        (a band of constant surface width).
    band_distance : float, optional
        Fraction of ``scale`` for ``band_mode="distance"``.
    match_size : int, optional
        Largest image side used for matching (the image is block-averaged
        down to it; texture coordinates still refer to the full image).
    flattening : {"mean_value", "stable_base"}, optional
        Coordinates of the recursive barycentric flattening (eq. 1), see
        :func:`geotex.patches.flatten.barycentric_hierarchy`:
        ``"stable_base"`` is the paper's (three parent corners with the
        smallest coordinates), which folds faces where neighbouring vertices
        pick different corners; ``"mean_value"`` is smooth.
    snap : float, optional
        Shared border vertices whose coordinates differ from the
        neighbour's by less than this many (full-resolution) pixels take
        the neighbour's.
    relax : bool, optional
        Run the local edge relaxation (Fig. 6).
    face_match : bool, optional
        At the face level, match the remaining faces (in groups of
        ``face_group`` adjacent faces, then one by one) like clusters, and
        unfold from a textured neighbour only the faces that still match
        worse than ``max_error``; ``False`` unfolds them all (the behaviour
        before face-level matching).
    face_group : int, optional
        Largest number of adjacent faces matched together at the face level.
        Default: 4 without a field, 1 (every face alone) with one.  With a
        field the groups failed four times in five on Spot 10k (slate tiles,
        rough metal) and were retried face by face anyway; alone
        from the start, seeds 0-2, the seams (patch borders and where the map
        jumps), stretch, rotation across borders and orientation breaks were
        as good or better on slate tiles and rough metal and equal on bricks,
        for 5-10 % less CPU.  Without a field 1 gave lower seams too but more
        rotation across borders (75th percentile +2 to +5 degrees on gravel,
        water and peppers) for 20-30 % more CPU.
    subpixel : bool, optional
        Refine the FFT minimum below the pixel and orientation grids
        (parabolas of the continuous mask error in x, y and the angle) and
        compare the candidates by that error.  Off by default: on Spot it
        did not lower the seam contrast (it made exact continuations of the
        neighbours lose to refined matches, see the module docstring).
    structure : bool, optional
        Use the sample's pattern (:func:`geotex.image.fftmatch.pattern_scale`,
        paper §5.1-5.2).  An anisotropic sample (structure-tensor coherence
        above ``ANISOTROPIC_COHERENCE`` = 0.3; the isotropic quilting samples
        and water measure 0.06-0.22, bricks 0.37, slate tiles 0.77) gets a
        band ``1 + coherence`` times wider.  A periodic sample gets a band of
        at least ``PATTERN_BAND`` = half a period (the mask then holds half a
        pattern cell across the border), its neighbours' continuations moved
        by whole periods as extra candidates (the exact continuation leaves a
        non-toroidal image after a few patches, a move by a lattice vector
        keeps the pattern's phase and orientation; such a continuation is
        kept whenever its error is below ``max_error``, not only when it
        beats the FFT minimum), the minimal patch size below, and the
        lattice snapping of border vertices (module docstring; measured on
        Spot 10k, Bob and Fertility with basket weave, bricks and rope net,
        seeds 0-1: rotation across patch borders, median 4.5-10.8 -> 0.9-4.7
        degrees, the colour jump where the map is discontinuous 0.00-0.14
        higher, patch-border contrast and stretch within +-0.05, CPU time
        not higher; benchmarks/results/hpm.md section 6).  Stochastic
        samples (no repeat, coherence <= 0.3: gravel, water, peppers) are
        mapped exactly as with ``False``.
    min_patch : float, optional
        For a periodic sample, in periods: a cluster whose children are
        smaller (mean equivalent-disc diameter) than ``min_patch`` periods
        keeps its best match even above ``max_error`` instead of being split
        (and prefers a neighbour's continuation then); ``0`` never.  The
        paper says patches should not be smaller than the pattern (1); on
        Spot 10k (seeds 0-2) 1 made the colour jump where the map is
        discontinuous worse (bricks 1.46 -> 1.78, basket weave 1.30 -> 1.67
        times the jump within patches) and did not keep the rows' orientation
        (rotation across borders, median 12 -> 13 degrees), 0 kept it best
        (4 degrees, seams unchanged) but took 2-2.5 times the CPU time (22 s
        on bricks), and 0.3 (only clusters of a few faces, whose children are
        single faces, are forced on these images) kept it (7 degrees) within
        the time budget, with seams between the two (1.67 / 1.55).
    progress : callable, optional
        Called with a stage name as work proceeds.

    Returns
    -------
    HPMResult

    Raises
    ------
    InputError
        On a bad mesh (open, non-manifold), image or option, or a scale so
        small that faces are larger than half the image.
    """
    V, F = as_mesh_arrays(V, F)
    m = F.shape[0]
    if m == 0:
        raise InputError("the base mesh has no faces")
    check_hpm_base(V, F)
    img = _image_arg(image)
    scale = positive_number(scale, name="scale")
    orientations = count(orientations, name="orientations")
    max_error = positive_number(max_error, name="max_error")
    max_flat_error = positive_number(max_flat_error, name="max_flat_error")
    band = positive_number(band, name="band")
    band_distance = positive_number(band_distance, name="band_distance")
    if band_mode not in ("topological", "distance"):
        raise InputError(f"band_mode must be 'topological' or 'distance', got {band_mode!r}")
    match_size = count(match_size, name="match_size", minimum=16)
    if flattening not in ("mean_value", "stable_base"):
        raise InputError(f"flattening must be 'mean_value' or 'stable_base', got "
                         f"{flattening!r}")
    snap = finite_number(snap, name="snap")
    if face_group is not None:
        face_group = count(face_group, name="face_group")
    if angle is not None:
        angle = finite_number(angle, name="angle")
    H_img, W_img = img.shape[:2]
    spread = None
    if orientation_spread is not None:
        spread = np.radians(finite_number(orientation_spread, name="orientation_spread"))
        if spread < 0:
            raise InputError(f"orientation_spread must be >= 0 degrees or None, got "
                             f"{orientation_spread!r}")
    ppm = W_img / scale                                   # full-res pixels per mesh unit
    elen = np.linalg.norm(V[F] - V[np.roll(F, -1, axis=1)], axis=2).mean()
    if elen * ppm > 0.5 * min(W_img, H_img):
        raise InputError(f"scale {scale:g} is too small for this mesh: its edges average "
                         f"{elen:.3g} units, more than half the image; give a scale of at "
                         f"least {2.0 * elen * W_img / min(W_img, H_img):.3g}")
    rng = np.random.default_rng(seed)
    # compiled bilinear sampling, rasterization and energy assembly (the same values): on
    # small bases loading numba costs more than the thousands of small calls save
    fast = m >= min(SAMPLE_JIT_FACES, JIT_MIN_SIZE)
    report(progress, "hierarchy")
    Hc = cluster_hierarchy(V, F, seed=int(rng.integers(2**31)))
    bh = barycentric_hierarchy(V, F, Hc, coordinates=flattening)
    L = len(Hc.levels)
    adj = face_adjacency(V, F)
    FF = adj.face_neighbors
    A = face_areas(V, F)
    # matching resolution
    f = max(1, int(np.ceil(max(H_img, W_img) / match_size)))
    rgb = img.astype(np.float64) / 255.0
    full = opponent_colors(rgb)
    small = _block_mean(full, f)
    report(progress, "spectra")
    spectra = texture_spectra(small, orientations=orientations)
    hm, wm = small.shape[:2]
    ppm_m = ppm / f
    center = spectra.center
    var2 = 2.0 * max(spectra.variance, 1e-12)
    ps = pattern_scale(img)
    # field: per-face direction (the user's, or a smooth field for a structured sample)
    if orientation_field not in ("auto", "always", "never"):
        raise InputError(f"orientation_field must be 'auto', 'always' or 'never', got "
                         f"{orientation_field!r}")
    field_tol = np.radians(finite_number(field_tolerance, name="field_tolerance"))
    if field_tol < 0:
        raise InputError(f"field_tolerance must be >= 0 degrees, got {field_tolerance!r}")
    fvec = None
    sym = 1
    auto_field = False
    if field is not None:
        fvec = np.asarray(getattr(field, "vectors", field), dtype=np.float64)
        if fvec.shape != (m, 3):
            raise InputError(f"field has {fvec.shape[0]} faces, the mesh {m}")
        sym = max(int(getattr(field, "symmetry", 1)), 1)
        if sym > 1:                      # one representative per face, combed
            fvec = comb_direction_field(V, F, fvec, symmetry=sym).vectors
    elif orientation_field == "always" or (orientation_field == "auto" and structure and (
            ps.periodic or ps.coherence > ANISOTROPIC_COHERENCE)):
        report(progress, "field")
        fvec, sym = _pattern_field(V, F, img, angle)
        auto_field = True
    # vertex graph for band distances (both directions stored: searched as directed, which
    # spares scipy a transpose per search)
    E = edge_topology(F, V.shape[0]).edges
    ew = np.linalg.norm(V[E[:, 0]] - V[E[:, 1]], axis=1)
    G = sp.csr_matrix((np.concatenate([ew, ew]), (np.concatenate([E[:, 0], E[:, 1]]),
                                                  np.concatenate([E[:, 1], E[:, 0]]))),
                      shape=(V.shape[0],) * 2)
    # per face, the field vector in its edge vectors (carried by any linear map of the face)
    fcoef = field_coefficients(V, F, fvec) if fvec is not None else None
    # per-vertex 2D positions of one fit (a face's flattening, its band's, scratch), read
    # back only on the rows just set: not cleared between fits
    scratch2, scratch_b, scratch_l = (np.zeros((V.shape[0], 2)) for _ in range(3))
    graph = (G.indptr.astype(np.int64), G.indices.astype(np.int64), G.data)
    vf = vertex_faces(F, V.shape[0]) if fast else None
    band_w = band_distance * scale
    patch_factor = finite_number(min_patch, name="min_patch")
    if patch_factor < 0:
        raise InputError(f"min_patch must be >= 0 periods, got {min_patch!r}")
    min_patch = 0.0
    if structure:
        if ps.coherence > ANISOTROPIC_COHERENCE:
            band_w *= 1.0 + ps.coherence
        if ps.periodic:
            size = _pattern_size(ps, img.shape)
            band_w = max(band_w, PATTERN_BAND * size / ppm)
            min_patch = patch_factor * size / ppm
    lattice = None                       # whole-period moves of a periodic sample (pixels)
    if structure and ps.periodic:
        p1 = ps.periods[0]
        q = ps.periods[1] if ps.periods.shape[0] > 1 else \
            np.array([-p1[1], p1[0]])           # stripes: along them, by one period
        K = int(np.ceil(max(W_img, H_img) / max(min(np.linalg.norm(p1),
                                                     np.linalg.norm(q)), 1.0)))
        k1, k2 = np.meshgrid(np.arange(-K, K + 1), np.arange(-K, K + 1))
        lattice = k1.reshape(-1, 1) * p1 + k2.reshape(-1, 1) * q
        lattice = lattice[np.argsort(np.hypot(lattice[:, 0], lattice[:, 1]), kind="stable")]
        lattice = lattice[1:]                # without the zero move
        basis = np.array([p1, q], dtype=np.float64)          # rows: the two lattice vectors
        stripes = ps.periods.shape[0] == 1
        snap_tol = LATTICE_SNAP * min(np.linalg.norm(p1), np.linalg.norm(q))
    # continuation window (matching pixels, with a field): a quarter of the pattern size
    win = max(1, int(round(CONTINUATION_WINDOW * (_pattern_size(ps, img.shape) if ps.periodic
                                                  else ps.correlation_length) / f)))
    pattern_info = {"periodic": bool(ps.periodic), "period_px": ps.period,
                    "correlation_length_px": ps.correlation_length,
                    "coherence": ps.coherence, "min_patch": min_patch, "band_width": band_w}
    if fvec is not None:
        pattern_info["field"] = "auto" if auto_field else "given"
        pattern_info["field_symmetry"] = sym
    # equivalent-disc diameter of every cluster, per level (for the minimal patch size)
    diam = [2.0 * np.sqrt(np.bincount(lv.labels, weights=A, minlength=lv.n_clusters) / np.pi)
            for lv in Hc.levels]

    def children_small(li, c):
        """Whether the children of cluster ``c`` of level ``li`` are smaller (mean
        equivalent-disc diameter) than the pattern: it is then not subdivided."""
        if min_patch <= 0.0 or li + 1 >= L:
            return False
        ch = Hc.children(li, c)
        return bool(ch.size and diam[li + 1][ch].mean() < min_patch)
    placements = []                      # (level, cluster) of every placement
    st = _State(V, F, m)
    levels = [HPMLevel(level=i, clusters=Hc.levels[i].n_clusters) for i in range(L)]

    frames = {}

    def frame(li):
        if li not in frames:
            lv = Hc.levels[li]
            direction = None
            if fvec is not None:
                first = np.full(lv.n_clusters, -1, np.int64)
                first[lv.labels[::-1]] = np.arange(m)[::-1]
                ref = fvec[first]
                sgn = np.sign(np.sum(fvec * ref[lv.labels], axis=1))
                sgn[sgn == 0] = 1.0
                w = (fvec * sgn[:, None]) * A[:, None]
                direction = np.stack([np.bincount(lv.labels, weights=w[:, i],
                                                  minlength=lv.n_clusters) for i in range(3)], 1)
                direction[np.linalg.norm(direction, axis=1) == 0] = ref[
                    np.linalg.norm(direction, axis=1) == 0]
            frames[li] = cluster_frames(V, F, lv.labels, lv.n_clusters, direction)
        return frames[li]

    polygons = {}                        # (level, cluster) -> its control polygon (read only)

    def flatten(li, c, fixed=None, fixed_mask=None):
        poly = polygons.get((li, c))
        if poly is None:
            e1, e2 = frame(li)[1:]
            poly = polygons[(li, c)] = control_polygon(V, Hc.levels[li].controls(c), e1[c],
                                                       e2[c])
        verts, loc, faces = flatten_cluster(bh, li, c, poly, fixed=fixed, fixed_mask=fixed_mask)
        return poly, verts, loc, faces

    def folded(verts, loc, faces):
        """Whether some face of the cluster is reversed or collapsed in ``loc``."""
        U = scratch2
        U[verts] = loc
        t = U[F[faces]]
        d = (t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1]) \
            - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0])
        return bool((d <= 1e-12 * np.abs(d).max()).any())

    def flat_error(verts, loc, faces):
        U = scratch2
        U[verts] = loc
        t = U[F[faces]]
        d = (t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1]) \
            - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0])
        a2 = 0.5 * d.sum()
        if a2 <= 0 or (d <= 0).any():
            return np.inf
        return abs(A[faces].sum() / a2 - 1.0)

    pflip = np.array([ppm_m, -ppm_m])

    def pix(loc):
        """Local coords (mesh units) -> matching pixels; image rows grow downwards, so
        the local y axis is flipped to keep the texture unmirrored on the surface."""
        return loc * pflip               # (x, -y) * ppm_m, the same values

    def field_direction(verts, loc, faces):
        """The field's direction in the matching-pixel frame of a flattened cluster.

        Every face's field vector is carried by the face's own linear map
        (surface -> flattening -> matching pixels); the area-weighted mean of
        ``exp(i N phi)`` gives the direction (radians, one of the ``N``
        representatives) and its coherence (1: the field is parallel in the
        flattening, 0: it turns all the way round, e.g. about a singularity).
        """
        return field_angle(verts, pix(loc), faces)

    def field_angle(verts, X2, faces):
        """:func:`field_direction` for any 2D positions ``X2`` of ``verts`` (no mirror)."""
        U = scratch2
        U[verts] = X2
        T = U[F[faces]]
        D = np.empty((T.shape[0], 2, 2))                                   # (k, 2, 2)
        D[:, :, 0] = T[:, 1] - T[:, 0]
        D[:, :, 1] = T[:, 2] - T[:, 0]
        d = (D @ fcoef[faces])[:, :, 0]
        w = A[faces]
        phi = np.arctan2(d[:, 1], d[:, 0])
        z = np.sum(w * np.exp(1j * sym * phi))
        tot = float(w.sum())
        a = float(np.angle(z)) / sym
        if sym > 1:       # the representative nearest the (combed) vectors' own mean
            a1 = float(np.angle(np.sum(w * np.exp(1j * phi))))
            step = 2 * np.pi / sym
            a += step * np.round(((a1 - a) % (2 * np.pi)) / step)
        return a, (abs(z) / tot if tot > 0 else 0.0)

    def fft_placement(rot_k, shift):
        """(R, t) of a translation ``shift`` of the mask over rotated copy ``rot_k``:
        matching-image position = R pix + t."""
        a = spectra.angles[rot_k]
        c, s_ = np.cos(a), np.sin(a)
        R = np.array([[c, s_], [-s_, c]])
        return R, R @ (shift - center) + center

    def to_image(loc, R, t):
        """Local coords (mesh units) -> full-res image pixel positions."""
        return (pix(loc) @ R.T + t) * f

    def from_image(P, R, t):
        """Inverse of :func:`to_image`."""
        p = (P / f - t) @ R / ppm_m
        return p * FLIP_Y

    def neighbour_fits(bverts, bl, every):
        """Rigid placements continuing the neighbours' own coordinates.

        The band vertices whose texture coordinates agree, grouped by the
        neighbouring placement that textured them, give per placement a
        least-squares rotation + translation (matching pixels = R pix + t)
        from the cluster's frame to the image: that neighbour "positioned
        exactly next to" the cluster.  One placement per fit: the neighbours
        of a cluster are in general rotated with respect to each other, and a
        fit over all of them is no rigid motion of any (on Spot with bricks
        its median residual was a third of the band's size, against 5 % for
        one neighbour).  The first fit is the main neighbour's (most band
        vertices): its rotation is the orientation that ``spread`` keeps and
        that the orientation grid is aligned on.  Without ``every`` only
        that one is returned; with it, every placement holding at least
        three band vertices gives one.
        """
        A = st.agreed()[bverts] / f
        ok = np.flatnonzero(np.isfinite(A[:, 0]))
        if ok.size < 3:
            return []
        pv = st.vpatch[bverts[ok]]
        u, cn = np.unique(pv, return_counts=True)
        order = np.argsort(-cn, kind="stable")
        if cn.max() < 3:
            sets = [ok]
        else:
            sets = [ok[pv == u[k]] for k in (order if every else order[:1]) if cn[k] >= 3]
        out = []
        for sel in sets:
            fit_ = _rigid_fit(pix(bl[bverts[sel]]), A[sel])
            if fit_ is not None:
                out.append(fit_)
        return out

    def turn_centre(bverts, bl, in_c):
        """The point (matching pixels, cluster frame) about which :func:`turned_fit`
        turns the neighbours' placements: the mean of the band vertices that belong
        to the cluster and agree, or of all agreeing band vertices."""
        Ab = st.agreed()[bverts] / f
        ok = np.isfinite(Ab[:, 0])
        on = ok & in_c[bverts]
        sel = on if on.sum() >= 2 else ok
        return pix(bl[bverts[sel]]).mean(axis=0)

    def turned_fit(fk, x0, a):
        """Placement ``fk`` (R, t) turned to orientation ``a`` (radians) about the
        texture position of its shared border, ``x0`` (:func:`turn_centre`).  Near
        that border the neighbour's pattern keeps its phase; the turn that is
        needed to follow the field spreads away from it."""
        y0 = fk[0] @ x0 + fk[1]
        Ra = np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
        return Ra, y0 - Ra @ x0

    def mask_points(tb, origin):
        """Raster-frame positions ``q`` (k, 2) of the mask pixels ``tb``."""
        ty, tx = np.divmod(tb, wm)
        return np.stack([tx + 0.5, ty + 0.5], 1) + origin

    def band_error(R, t, q, Itb):
        """Squared mask error of the placement ``R q + t`` of the mask pixels at ``q``
        (raster frame, :func:`mask_points`) with colours ``Itb``."""
        S = _sample(small, q @ R.T + t, fast)
        return float(np.sum((Itb - S) ** 2))

    def lattice_continuation(cont, fits, Rd, loc, q, Itb, li):
        """The best continuation of a neighbour moved by whole periods of the pattern.

        A periodic sample shows the same pattern at ``t + k1 p1 + k2 p2``: when
        the exact continuation of a neighbour leaves the image (the sample is
        not toroidal), the same continuation moved by a lattice vector keeps
        the pattern's phase and orientation across the border.  The moves
        that keep the cluster's bounding box inside the image are tried, the
        ``LATTICE_CANDIDATES`` shortest, and the lowest band error among them
        and ``cont`` (when inside) is returned.
        """
        cont_in = inside_image(to_image(loc, cont[0] @ Rd, cont[1]))
        lim = np.array([W_img, H_img], dtype=np.float64)
        for Rk, tk in fits:
            P0 = to_image(loc, Rk, tk)
            lo, hi = P0.min(axis=0), P0.max(axis=0)
            ok = np.all((lo + lattice >= 0) & (hi + lattice <= lim), axis=1)
            shifts = lattice[np.flatnonzero(ok)[:LATTICE_CANDIDATES]]
            if not shifts.size:
                continue
            Rr = Rk @ Rd.T
            t2s = tk + shifts / f                               # (s, 2), one per move
            # every move's band error in one batched bilinear lookup (the same values
            # and per-move sums as one band_error call per move)
            qR = q @ Rr.T
            S = _sample(small, (qR[None] + t2s[:, None]).reshape(-1, 2), fast)
            D = (Itb[None] - S.reshape(t2s.shape[0], q.shape[0], -1)) ** 2
            for i, ek in enumerate(D.reshape(t2s.shape[0], -1).sum(axis=1).tolist()):
                if ek < cont[2] or not cont_in:
                    cont, cont_in = (Rr, t2s[i], ek), True
        return cont

    def field_continuation(fits, Rd, loc, Eg, origin, k_ref):
        """With a field: the best continuation of the neighbours ``fits`` (already turned
        onto the searched orientation ``k_ref``) as ``(R, t, error)`` in the turned raster
        frame, or None.

        Every neighbour's continuation and, for a periodic sample, its
        ``LATTICE_CANDIDATES`` shortest moves by whole periods that keep the
        cluster's bounding box inside the image (see :func:`lattice_continuation`)
        is moved to the lowest energy of ``Eg`` (the FFT energies of the searched
        orientation) within ``win`` matching pixels of it; the lowest of these
        positions whose faces stay inside the image is returned, with that energy.
        (Before, the moves were ranked by their bilinear band error and only the
        best one was moved to its window's minimum.)
        """
        ts = []
        lim = np.array([W_img, H_img], dtype=np.float64)
        for Rk, tk in fits:
            ts.append(tk[None])
            if lattice is not None:
                P0 = to_image(loc, Rk, tk)
                lo, hi = P0.min(axis=0), P0.max(axis=0)
                ok = np.all((lo + lattice >= 0) & (hi + lattice <= lim), axis=1)
                ts.append(tk + lattice[np.flatnonzero(ok)[:LATTICE_CANDIDATES]] / f)
        T = np.concatenate(ts)
        rk = spectra.angles[k_ref]
        Rk_ = np.array([[np.cos(rk), np.sin(rk)], [-np.sin(rk), np.cos(rk)]])
        sxy = np.rint((T - center) @ Rk_ + center + origin).astype(np.int64)
        wmin = _window_minima if fast else _window_minima.py_func
        val, by, bx = wmin(Eg[0], sxy[:, 0], sxy[:, 1], win)
        for i in np.argsort(val, kind="stable"):
            if not np.isfinite(val[i]):
                break
            Rw, tw = fft_placement(k_ref, np.array([bx[i], by[i]], dtype=np.float64) - origin)
            if inside_image(to_image(loc, Rw @ Rd, tw)):
                return Rw, tw, float(val[i])
        return None

    def quick_continuation(c, fits, Rd, loc, q, Itb, nJ):
        """At the face level with a field: the neighbours' continuations (already turned
        onto the field's direction) whose band error is below ``max_error`` and whose
        faces stay inside the image; the lowest as ``(R, t, error)`` in the turned raster
        frame, or None (then the FFT search decides)."""
        if c is not None or fvec is None or subpixel or not fits:
            return None
        lim = max_error * nJ * var2
        out = None
        for Rk, tk in fits:
            ek = band_error(Rk @ Rd.T, tk, q, Itb)
            if ek <= lim and (out is None or ek < out[2]) and \
                    inside_image(to_image(loc, Rk, tk)):
                out = (Rk @ Rd.T, tk, ek)
        return out

    def inside_image(P):
        return bool((P[:, 0] >= 0).all() and (P[:, 0] <= W_img).all()
                    and (P[:, 1] >= 0).all() and (P[:, 1] <= H_img).all())

    def vertex_uv_of_done(verts):
        """Mean full-res position of each vertex over textured faces (nan if none)."""
        return st.agreed()[verts]

    # the mask planes of the fits (footprint K, colours I, support J), kept zero between
    # fits: each fit sets the pixels it draws (``drawn``) and the next one clears them
    planes = (np.zeros(hm * wm), np.zeros((hm * wm, small.shape[2])), np.zeros(hm * wm))
    drawn = []

    def raster_planes():
        """The planes (K, I, J), all zero."""
        for ix in drawn:
            for plane in planes:
                plane[ix] = 0.0
        drawn.clear()
        return planes

    def distance_band(src):
        """The textured faces whose vertices lie within ``band_w`` of ``src`` along
        mesh edges (compiled from ``SAMPLE_JIT_FACES`` faces: the same faces)."""
        if fast:
            return textured_band(graph, src, band_w, vf, F, st.done)
        dist = dijkstra(G, directed=True, indices=src, min_only=True, limit=band_w)
        return np.flatnonzero(st.done & np.isfinite(dist)[F].all(axis=1))

    def topological_band(in_c, faces):
        """Union of the bands of the textured neighbour clusters along this cluster."""
        nbf = FF[faces].ravel()
        nbf = nbf[(nbf >= 0)]
        pids = np.unique(st.patch[nbf[st.done[nbf]]])
        out = []
        for pid in pids[pids >= 0]:
            if placements[int(pid)][1] is None:
                continue                 # a face-level group: no control polygon
            ly, cy = placements[int(pid)]
            lvy = Hc.levels[ly]
            loop = lvy.boundary_loop(cy)
            ctrl = lvy.controls(cy)
            if loop.size == 0 or ctrl.size < 2:
                continue
            shared = in_c[loop] & in_c[np.roll(loop, -1)]      # loop edge j -> j + 1 on X
            corner = np.isin(loop, ctrl)
            edge_of = (np.cumsum(corner) - 1) % ctrl.size        # polygon edge of loop edge j
            edges = np.unique(edge_of[shared])
            if edges.size:
                out.append(edge_band(bh, ly, cy, edges, width=band))
        return np.unique(np.concatenate(out)) if out else np.zeros(0, np.int64)

    def refuse(li, reason):
        levels[li].refused[reason] = levels[li].refused.get(reason, 0) + 1

    def group_frames(gs):
        """Mean-plane frames ``(e1, e2)`` (k, 3) of the groups of faces ``gs`` (face
        level), all at once: each group's rows are those of a call of
        :func:`geotex.patches.flatten.cluster_frames` on that group alone."""
        direction = None
        if fvec is not None:
            direction = np.zeros((len(gs), 3))
            for i, faces in enumerate(gs):
                ref = fvec[faces[0]]
                sgn = np.where(fvec[faces] @ ref < 0, -1.0, 1.0)
                direction[i] = (np.sum(fvec[faces] * (sgn * A[faces])[:, None], axis=0)
                                if A[faces].sum() > 0 else ref)
        lab = np.repeat(np.arange(len(gs)), [g.size for g in gs])
        _, e1, e2 = cluster_frames(V, F[np.concatenate(gs)], lab, len(gs), direction)
        return e1, e2

    def place(li, c, group=None, force=False, gframe=None):
        """Try to texture cluster c of level li; returns the relative error or None.

        With ``group`` (face level), the faces ``group`` are textured instead,
        flattened by projection onto their mean plane, whose axes ``gframe``
        (e1, e2) are given (:func:`group_frames`).  With ``force`` the best
        match is kept even above ``max_error`` (children smaller than the
        pattern).
        """
        if group is not None:
            faces = np.asarray(group, np.int64)
            verts = np.unique(F[faces])
            e1c, e2c = gframe
            loc = np.stack([V[verts] @ e1c, V[verts] @ e2c], 1)
            if flat_error(verts, loc, faces) > max_flat_error:
                refuse(li, 'flattening')
                return None
            return fit(li, None, verts, loc, faces, True, e1c, e2c, None)
        lv = Hc.levels[li]
        if not lv.disc[c] or lv.control_ptr[c + 1] - lv.control_ptr[c] < 3:
            refuse(li, 'not_disc')
            return None
        last = li == L - 2               # finest cluster level: flatten as well as possible
        poly, verts, loc, faces = flatten(li, c)
        N, e1, e2 = frame(li)
        proj = False
        if flat_error(verts, loc, faces) > max_flat_error:
            if not last:
                refuse(li, 'flattening')
                return None
            # the barycentric recursion folds this small cluster (its vertices take
            # their coordinates from different base triangles of a polygon laid out
            # with 3D lengths): flatten it by projection onto its mean plane instead
            verts = np.unique(F[faces])
            loc = np.stack([V[verts] @ e1[c], V[verts] @ e2[c]], 1)
            if flat_error(verts, loc, faces) > max_flat_error:
                refuse(li, 'flattening')
                return None
            levels[li].projected += 1
            proj = True
        return fit(li, c, verts, loc, faces, proj, e1[c], e2[c], poly, force)

    def fit(li, c, verts, loc, faces, proj, e1c, e2c, poly, force=False):
        """Match and texture the flattened faces ``faces`` (cluster ``c`` of level ``li``,
        or a face-level group when ``c`` is None: then ``proj`` is True)."""
        last = c is None or li == L - 2
        if c is not None:
            lv = Hc.levels[li]
            N = frame(li)[0]
        if fvec is not None:
            a_fld, coh = field_direction(verts, loc, faces)
            if coh < FIELD_COHERENCE and not last:
                refuse(li, 'field_turns')    # the field turns too much for one rigid patch
                return None
        # band of textured faces within band_w of the cluster
        in_c = np.zeros(V.shape[0], bool)
        in_c[verts] = True
        src = verts[st.vcnt[verts] > 0]  # (the sources' order does not change the band)
        band_faces = np.zeros(0, np.int64)
        fixed = fixed_mask = None
        if src.size and (band_mode == "distance" or c is None):
            band_faces = distance_band(src)  # (at the face level whatever band_mode)
        elif src.size:
            band_faces = topological_band(in_c, faces)
        if band_faces.size:
            bverts = np.unique(F[band_faces])
            if proj:
                bloc = np.stack([V[bverts] @ e1c, V[bverts] @ e2c], 1)
            else:
                idx, w = polygon_coordinates(V, lv.controls(c), N[c], e1c, e2c, V[bverts])
                bloc = np.einsum("pk,pkd->pd", w, poly[idx])
                fixed = np.zeros((V.shape[0], 2))
                fixed_mask = np.zeros(V.shape[0], bool)
                fixed[bverts] = bloc
                shared = np.intersect1d(bverts, verts)
                fixed_mask[shared] = True
                poly, verts2, loc2, faces = flatten(li, c, fixed, fixed_mask)
                if folded(verts2, loc2, faces):
                    if not last:
                        refuse(li, 'border_folds')
                        return None          # imposing the border folded the map: subdivide
                    # finest cluster level: keep the free flattening (border cracks
                    # are then left to the snapping and the relaxation)
                    levels[li].free_border += 1
                    fixed = fixed_mask = None
                else:
                    verts, loc = verts2, loc2
            bl = scratch_b               # read on the band's vertices only
            bl[bverts] = bloc
        Lall = scratch_l                 # read on the faces' vertices only
        Lall[verts] = loc
        # orientation grid: the raster frame is turned so that the reference orientation
        # is exactly one of the searched orientations (the FFT candidates then include it,
        # and the others lie at multiples of 360 / orientations degrees from it).  Without
        # a field the reference is the main neighbour's orientation (its exact
        # continuation is then a candidate); with a field it is the field's direction in
        # the cluster (the representative nearest the main neighbour's orientation), and
        # only the neighbours' continuations within ``field_tol`` of it are candidates
        nfit = None
        fits = []
        Rd = np.eye(2)
        a_ref = None
        if fvec is not None:
            a_ref = a_fld
        if band_faces.size and st.n_patch > 0:
            fits = neighbour_fits(bverts, bl, c is None)
            nfit = fits[0] if fits else None
            if fvec is not None:
                if nfit is not None:
                    a_nb = np.arctan2(nfit[0][0, 1], nfit[0][0, 0])
                    step = 2 * np.pi / sym
                    a_ref = a_fld + step * np.round(((a_nb - a_fld) % (2 * np.pi)) / step)
                    # the neighbours' continuations turned to the field's direction (about
                    # their shared border), those that need at most ``field_tol``
                    turned = []
                    x0 = turn_centre(bverts, bl, in_c)
                    for fk in fits:
                        ak = np.arctan2(fk[0][0, 1], fk[0][0, 0])
                        if _angle_gap(ak, a_ref, sym) <= field_tol + 1e-12:
                            ar = a_fld + step * np.round(((ak - a_fld) % (2 * np.pi)) / step)
                            turned.append(turned_fit(fk, x0, ar))
                    fits = turned
                    nfit = fits[0] if fits else None
                    levels[li].field_refused += int(nfit is None)
            elif nfit is not None:
                a_ref = np.arctan2(nfit[0][0, 1], nfit[0][0, 0])
        k_ref = None
        if a_ref is not None:
            dev = (spectra.angles - a_ref + np.pi) % (2 * np.pi) - np.pi
            k_ref = int(np.argmin(np.abs(dev)))
            dl = -dev[k_ref]                                    # a_ref - nearest angle
            Rd = np.array([[np.cos(dl), np.sin(dl)], [-np.sin(dl), np.cos(dl)]])

        def qpix(x):
            return pix(x) @ Rd.T

        # raster: footprint = cluster + band, origin at its bbox corner
        pts = loc if not band_faces.size else np.vstack([loc, bl[bverts]])
        pp = qpix(pts)
        origin = np.floor(pp.min(axis=0)) - 1.0
        ext = np.ceil(pp.max(axis=0)) - origin + 1.0
        if ext[0] >= wm or ext[1] >= hm:
            refuse(li, 'too_large')
            return None
        tri_c = qpix(Lall[F[faces]].reshape(-1, 2)).reshape(-1, 3, 2) - origin
        K, I, J = raster_planes()
        t_, _, _ = rasterize_triangles(tri_c, wm, hm, fast=fast)
        K[t_] = 1.0
        drawn.append(t_)
        nJ = 0.0                         # mask pixels (J.sum(): an exact count)
        if band_faces.size:
            tri_b = qpix(bl[F[band_faces]].reshape(-1, 2)).reshape(-1, 3, 2) - origin
            tb, fb, bb = rasterize_triangles(tri_b, wm, hm, fast=fast)
            uvb = np.einsum("tk,tkd->td", bb, st.corner[band_faces[fb]]) / f
            I[tb] = _sample(small, uvb, fast)
            J[tb] = 1.0
            K[tb] = 1.0
            drawn.append(tb)
            nJ = float(np.count_nonzero(J))
            qb, Itb = mask_points(tb, origin), I[tb]     # the mask pixels and their colours
        K = K.reshape(hm, wm)
        kpix = np.concatenate(drawn)     # the footprint's pixels (K > 0), for match_energy
        # face level with a field: a neighbour's continuation under the threshold is taken
        # without the FFT search (module docstring, 5.)
        quick = None if li == 0 or not nJ else \
            quick_continuation(c, fits, Rd, loc, qb, Itb, nJ)
        if li == 0 or not nJ:
            which = None
            if fvec is not None:         # the field's direction (the combed representative)
                which = [k_ref]
            elif st.n_patch == 0:
                a0 = np.radians(angle) if angle is not None else rng.random() * 2 * np.pi
                which = [int(np.argmin(np.abs((spectra.angles - a0 + np.pi) % (2 * np.pi)
                                              - np.pi)))]
            Eg = match_energy(spectra, I.reshape(hm, wm, -1), J.reshape(hm, wm), K,
                              which=which, fast=fast, footprint_pixels=kpix)
            okp = np.flatnonzero(np.isfinite(Eg.ravel()))
            if okp.size == 0:
                refuse(li, 'no_position')
                return None
            pick = okp[int(rng.integers(okp.size))]
            refined = None
            err = 0.0
        elif quick is not None:
            cont, pick, refined = quick, None, None
            err = quick[2] / nJ / var2
            levels[li].continued += 1
            levels[li].quick += 1
        else:
            which = None
            if fvec is not None:
                # the field gives the orientation: only its direction (the representative
                # next to the main neighbour's, without a neighbour fit the combed one)
                which = [k_ref]
            elif nfit is not None and spread is not None:
                # orientation propagates from the neighbours (paper §3): only the
                # orientations within ``spread`` of the neighbour's own are searched
                Rm = nfit[0] @ Rd.T                # the main neighbour's orientation
                a_nb = np.arctan2(Rm[0, 1], Rm[0, 0])
                dev = np.abs((spectra.angles - a_nb + np.pi) % (2 * np.pi) - np.pi)
                which = np.flatnonzero(dev <= spread + 1e-9)
                if which.size == 0:
                    which = np.array([int(np.argmin(dev))])
            Eg = match_energy(spectra, I.reshape(hm, wm, -1), J.reshape(hm, wm), K,
                              which=which, fast=fast, footprint_pixels=kpix)
            flat = Eg.ravel()
            if not np.isfinite(flat).any():
                refuse(li, 'no_position')
                return None
            best = float(flat.min())
            near = np.flatnonzero(flat <= best + 1e-9 * (1.0 + best))
            pick = near[int(rng.integers(near.size))]
            if (fvec is not None or nfit is None) and not (subpixel or force) \
                    and best / nJ / var2 > max_error:
                # refused whatever the continuations give: with a field a continuation is
                # taken at the FFT minimum near it (below), whose error is at least
                # ``best``; the continuations (the lattice moves above all) are not
                # evaluated for a cluster that is subdivided anyway
                refuse(li, 'error')
                return -best / nJ / var2
            cont = None
            if fvec is not None and nfit is not None:
                # with a field every continuation has the searched orientation: each
                # (and, for a periodic sample, each of its lattice moves) is taken at
                # the FFT minimum within ``CONTINUATION_WINDOW`` of a pattern size of it
                # (its phase corrected, e.g. after whole-period moves of a sample that is
                # not exactly periodic), and the lowest of these is the continuation
                cont = field_continuation(fits if c is None else fits[:1], Rd, loc, Eg,
                                          origin, k_ref)
            elif nfit is not None:
                # the neighbour's placement in the turned raster frame: R Rd^T q + t
                Rc = nfit[0] @ Rd.T
                cont = (Rc, nfit[1], band_error(Rc, nfit[1], qb, Itb))
                for Rk, tk in fits[1:]:          # face level: every neighbour's continuation
                    ek = band_error(Rk @ Rd.T, tk, qb, Itb)
                    if ek < cont[2] and inside_image(to_image(loc, Rk, tk)):
                        cont = (Rk @ Rd.T, tk, ek)
                if lattice is not None:
                    cont = lattice_continuation(cont, fits if c is None else fits[:1], Rd,
                                                loc, qb, Itb, li)
            refined = None
            if subpixel:
                # the FFT minimum lies on the pixel grid and on the orientation grid:
                # refine it, and compare every candidate by the same (continuous) E
                kk, dy, dx = np.unravel_index(pick, Eg.shape)
                rot_k = int(kk if which is None else np.asarray(which)[kk])
                R0, t0 = fft_placement(rot_k, np.array([dx, dy], dtype=np.float64) - origin)
                R1, t1, e_1 = _refine_placement(small, R0, t0, qb, Itb,
                                                np.pi / orientations, fast)
                if inside_image(to_image(loc, R1 @ Rd, t1)):
                    refined, best = (R1, t1), e_1
                else:
                    best = band_error(R0, t0, qb, Itb)
                pick = None if refined is not None else pick
            if cont is not None and (cont[2] <= best or (
                    lattice is not None and (force or cont[2] <= max_error * nJ * var2))):
                Pc = to_image(loc, cont[0] @ Rd, cont[1])
                if inside_image(Pc):
                    best, pick, refined = cont[2], None, None
            err = best / nJ / var2
            if err > max_error:
                if not force:
                    refuse(li, 'error')
                    return -err
                levels[li].forced += 1
            if pick is None and refined is None:
                levels[li].continued += 1
        if refined is not None:
            R_, t_ = refined
        elif pick is None:
            R_, t_ = cont[0], cont[1]
        else:
            kk, dy, dx = np.unravel_index(pick, Eg.shape)
            rot_k = int(kk if which is None else np.asarray(which)[kk])
            R_, t_ = fft_placement(rot_k, np.array([dx, dy], dtype=np.float64) - origin)
        R_ = R_ @ Rd                     # back from the turned raster frame
        P = to_image(loc, R_, t_)
        # border cracks: snap to the neighbour's coordinates where they (nearly) agree
        nb_uv = vertex_uv_of_done(verts)
        has = np.isfinite(nb_uv[:, 0])
        if has.any():
            tri = np.searchsorted(verts, F[faces])
            nb0 = np.where(has[:, None], nb_uv, 0.0)     # (rows are all nan or finite)
            close = has & (np.linalg.norm(P - nb0, axis=1) <= snap)
            close = _snap(P, nb_uv, close, tri)

            def spread_moves(moved, keep, turn=FIELD_MOVE_TURN):
                """Spread the moves of border vertices inside the cluster through the
                recursive mapping (the moved vertices imposed at every level), as in the
                paper; ``keep`` rows stay where they are.  Returns the new positions, or
                None if that folds a face."""
                nonlocal fixed, fixed_mask
                mm = np.flatnonzero(np.any(moved != P, axis=1))
                if mm.size == 0:
                    return None
                if proj:
                    ok_ = not folded(verts, moved * FLIP_Y,
                                     faces) and not turns(moved, turn)
                    return moved if ok_ else None
                if fixed is None:
                    fixed = np.zeros((V.shape[0], 2))
                    fixed_mask = np.zeros(V.shape[0], bool)
                fx0, fm0 = fixed.copy(), fixed_mask.copy()
                fixed[verts[mm]] = from_image(moved[mm], R_, t_)
                fixed_mask[verts[mm]] = True
                _, v2, loc2, f2 = flatten(li, c, fixed, fixed_mask)
                P2 = to_image(loc2, R_, t_)
                P2[keep] = moved[keep]
                if folded(verts, P2 * FLIP_Y, faces) or \
                        turns(P2, turn):
                    fixed, fixed_mask = fx0, fm0
                    return None
                return P2

            def turns(P2, turn):
                """With a field: whether the moves turn the patch away from its
                orientation by more than ``FIELD_MOVE_TURN`` degrees (spread by the
                recursive mapping, the relaxation's small border moves turned whole
                patches by 6 degrees (median) on a torus with stripes)."""
                if fvec is None:
                    return False
                # the angle of the current positions: that of the last accepted moves
                a0 = seen[1] if seen[0] is P else field_angle(verts, P, faces)[0]
                a1 = field_angle(verts, P2, faces)[0]
                seen[:] = [P2, a1]
                return _angle_gap(a1, a0, sym) > np.radians(turn)

            seen = [None, 0.0]               # (positions, their field angle) last computed

            if lattice is not None and (has & ~close).any():
                # periodic sample: a border vertex within ``snap_tol`` of a copy of the
                # neighbour's position moved by whole periods takes that copy (the map
                # jumps by a lattice vector there: same phase, no visible seam)
                d = P - nb0
                if stripes:            # one repeat: only the phase across the stripes
                    s_ = d @ basis[0] / (basis[0] @ basis[0])
                    target = P - (s_ - np.rint(s_))[:, None] * basis[0]
                else:
                    k = np.rint(np.linalg.solve(basis.T, d.T).T)
                    target = nb0 + k @ basis
                near_ = has & ~close & (np.linalg.norm(P - target, axis=1) <= snap_tol)
                if near_.any():
                    moved = P.copy()
                    got = _snap(moved, target, near_, tri)
                    P2 = spread_moves(moved, close | got, FIELD_SNAP_TURN)
                    if P2 is not None:
                        P = P2
                        close = close | got
                        levels[li].lattice_snapped += int(got.sum())
            if relax and (has & ~close).any():
                moved = _relax(P, verts, faces, has & ~close, F, st, full, rng, f, fast)
                P2 = spread_moves(moved, close)
                if P2 is not None:
                    P = P2
        vpos = scratch_l
        vpos[verts] = P
        st.mark(F, faces, vpos[F[faces]], st.n_patch, li)
        st.n_patch += 1
        placements.append((li, c))
        return err

    # ------------------------------------------------------------------
    # start: the flattest cluster of the coarsest level with a flat one
    report(progress, "start")
    start = None
    an = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    for li in range(L - 1):
        lv = Hc.levels[li]
        best = None
        # flatten only the clusters with the narrowest normal cone (|sum a n| / sum a)
        vec = np.stack([np.bincount(lv.labels, weights=an[:, i], minlength=lv.n_clusters)
                        for i in range(3)], 1)
        tot = np.bincount(lv.labels, weights=np.linalg.norm(an, axis=1),
                          minlength=lv.n_clusters)
        cone = np.linalg.norm(vec, axis=1) / np.maximum(tot, 1e-300)
        for c in np.argsort(-cone, kind="stable")[:8]:
            if not lv.disc[c] or lv.control_ptr[c + 1] - lv.control_ptr[c] < 3:
                continue
            _, verts, loc, faces = flatten(li, c)
            e = flat_error(verts, loc, faces)
            ext = np.ptp(loc, axis=0) * ppm_m
            if e <= max_flat_error and ext.max() < 0.9 * min(hm, wm) and (best is None
                                                                           or e < best[0]):
                best = (e, int(c))
        if best is not None:
            start = (li, best[1])
            break
    queues = [[] for _ in range(L)]
    if start is None:
        li0 = L - 1
    else:
        li0 = start[0]
        r = place(*start, force=children_small(*start))
        if r is None or r < 0:
            li0 = start[0] + 1
            for c in range(Hc.levels[start[0]].n_clusters):
                queues[li0].extend(Hc.children(start[0], c).tolist())
            levels[start[0]].subdivided += Hc.levels[start[0]].n_clusters
        else:
            levels[li0].placed += 1
            levels[li0].errors.append(0.0)
            queues[li0] = [c for c in range(Hc.levels[li0].n_clusters) if c != start[1]]
    if start is None:
        queues[li0] = list(range(Hc.levels[li0].n_clusters))

    outside = {}                         # (level, cluster) -> the faces across its border

    def priority(li, c):
        """Share of the faces across the border of cluster ``c`` that are textured."""
        nb = outside.get((li, c))
        if nb is None:
            lv = Hc.levels[li]
            lo, hi = Hc.descendants(li, c, L - 1)
            faces = np.flatnonzero((Hc.levels[-1].labels >= lo) & (Hc.levels[-1].labels < hi))
            nb = FF[faces]
            nb = outside[(li, c)] = nb[(nb >= 0) & (lv.labels[np.maximum(nb, 0)] != c)]
        return np.count_nonzero(st.done[nb]) / nb.size if nb.size else 0.0

    for li in range(li0, L):
        if li == L - 1:
            break
        report(progress, f"level {li}")
        heap = [(-priority(li, c), c) for c in queues[li]]
        heapq.heapify(heap)
        nxt = queues[li + 1]
        while heap:
            p, c = heapq.heappop(heap)
            q = -priority(li, c)
            if q < p - 1e-12 and heap:
                heapq.heappush(heap, (q, c))
                continue
            r = place(li, c, force=children_small(li, c))
            if r is None or r < 0:
                levels[li].subdivided += 1
                nxt.extend(Hc.children(li, c).tolist())
            else:
                levels[li].placed += 1
                levels[li].errors.append(r)
    # face level: the remaining faces, in small groups of adjacent faces, matched like
    # clusters (flattened by projection); a group that fails is retried face by face,
    # and a face that fails is unfolded from a textured neighbour
    report(progress, "faces")
    lf = L - 1
    if face_group is None:               # with a field the faces alone (see face_group)
        face_group = 1 if fvec is not None else 4
    groups = _face_groups(FF, ~st.done, face_group) if face_match else []
    # the frames of the groups and of their faces alone (a group that fails is retried
    # face by face), computed once
    if groups:
        ge1, ge2 = group_frames(groups)
        todo_f = np.concatenate(groups)
        fe1, fe2 = group_frames([todo_f[i:i + 1] for i in range(todo_f.size)])
        slot_f = np.full(m, -1, np.int64)
        slot_f[todo_f] = np.arange(todo_f.size)
        n_groups = len(groups)

    around = {}                          # group -> the faces across its border

    def group_priority(i):
        """Share of the faces across the border of group ``i`` that are textured."""
        nb = around.get(i)
        if nb is None:
            g = groups[i]
            nb = FF[g].ravel()
            nb = nb[nb >= 0]
            nb = around[i] = nb[~np.isin(nb, g)]
        return np.count_nonzero(st.done[nb]) / nb.size if nb.size else 0.0

    heap = [(-group_priority(i), i) for i in range(len(groups))]
    heapq.heapify(heap)
    while heap:
        p, i = heapq.heappop(heap)
        g = groups[i]
        q = -group_priority(i)
        if q < p - 1e-12 and heap:
            heapq.heappush(heap, (q, i))
            continue
        gfr = (ge1[i], ge2[i]) if i < n_groups else (fe1[slot_f[g[0]]], fe2[slot_f[g[0]]])
        r = place(lf, None, group=g, gframe=gfr)
        if r is None or r < 0:
            if g.size > 1:               # retry face by face
                levels[lf].subdivided += 1
                for fc in g:
                    groups.append(np.array([fc]))
                    heapq.heappush(heap, (-group_priority(len(groups) - 1), len(groups) - 1))
        else:
            levels[lf].placed += 1
            levels[lf].errors.append(r)
            levels[lf].matched_faces += g.size
    report(progress, "gaps")
    levels[-1].filled_faces = _fill_gaps(V, F, FF, st)
    # output: split vertices only where the corner positions differ
    uvpix = st.corner.reshape(-1, 2)
    uv = np.stack([uvpix[:, 0] / W_img, 1.0 - uvpix[:, 1] / H_img], 1)
    key = np.column_stack([F.ravel(), uv])
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    uv_out = uv[first[order]]
    uv_faces = rank[inv.ravel()].reshape(m, 3).astype(np.int64)
    if min_patch > 0.0 or (structure and ps.periodic):
        # how many pattern periods the patches span (area-weighted median over the faces of
        # the equivalent-disc diameter of the placement that textured them): below 1 the
        # patches are smaller than the pattern, whose structure is then lost (paper §5.2)
        placed_ = st.patch >= 0
        if placed_.any():
            pa = np.bincount(st.patch[placed_], weights=A[placed_])
            dia = 2.0 * np.sqrt(pa[st.patch[placed_]] / np.pi)
            o = np.argsort(dia, kind="stable")
            cw = np.cumsum(A[placed_][o])
            med = float(dia[o][np.searchsorted(cw, 0.5 * cw[-1])])
            pattern_info["patch_periods"] = med * ppm / _pattern_size(ps, img.shape)
    fl = np.where(st.face_level < 0, L - 1, st.face_level)
    return HPMResult(uv=np.ascontiguousarray(uv_out), uv_faces=uv_faces, patch=st.patch,
                     face_level=fl, levels=levels, pattern=pattern_info)


def _angle_gap(a: float, b: float, sym: int) -> float:
    """Smallest angle between direction ``a`` and the ``sym`` representatives of ``b``."""
    step = 2 * np.pi / sym
    return abs((a - b + 0.5 * step) % step - 0.5 * step)


def _pattern_field(V, F, img, angle):
    """Smooth direction field for a structured sample: (per-face vectors, symmetry).

    The smoothest field of the surface (:func:`geotex.fields.smooth_direction_field`,
    no constraint), with 4-fold symmetry when the sample looks the same turned by a
    quarter turn (:func:`geotex.image.fftmatch.quarter_turn_symmetry` above
    ``QUARTER_TURN``), 2-fold (lines) otherwise; turned by ``angle`` degrees about
    the normals when given (the smoothest field is defined up to such a turn).  The
    vectors are combed (:func:`geotex.fields.comb_direction_field`): a patch without a
    textured neighbour to continue takes the representative nearest them, so that
    separately started regions agree on the pattern's sign except across the
    combing's cut edges.
    """
    sym = 4 if quarter_turn_symmetry(img) >= QUARTER_TURN else 2
    # faces of zero area (simplified meshes have some) carry no direction: the field is
    # solved without them (they weigh nothing in a cluster's direction) and they get a
    # neighbour's vector, or the x axis
    bad = degenerate_faces(V, F)
    keep = np.setdiff1d(np.arange(F.shape[0]), bad)
    fld = smooth_direction_field(V, F[keep], symmetry=sym)
    sub = comb_direction_field(V, F[keep], fld).vectors
    if angle is not None:
        a = np.radians(angle)
        sub = np.cos(a) * sub + np.sin(a) * np.cross(fld.normals, sub)
    vec = np.zeros((F.shape[0], 3))
    vec[keep] = sub
    vec[bad] = (1.0, 0.0, 0.0)
    if bad.size and keep.size:
        FF = face_adjacency(V, F).face_neighbors
        for _ in range(bad.size):            # waves: each bad face from a good neighbour
            nb = FF[bad]
            good = np.isin(nb, keep) & (nb >= 0)
            has = good.any(axis=1)
            if not has.any():
                break
            vec[bad[has]] = vec[nb[has, np.argmax(good[has], axis=1)]]
            keep = np.union1d(keep, bad[has])
            bad = bad[~has]
            if bad.size == 0:
                break
    return np.ascontiguousarray(vec), sym


def _pattern_size(ps, shape) -> float:
    """Pattern size (pixels) behind the band width and the minimal patch size.

    The longest repeat of ``ps`` within a quarter of the image (the repeats
    confirmed at twice their length, see
    :func:`geotex.image.fftmatch.pattern_scale`): a second repeat found
    further (the basket weave's 61 px beside its 34 px) only enters the
    lattice (continuations moved by whole periods, lattice snapping).  With it as the pattern
    size, the wider band and the larger forced clusters made the seams and
    the rotation across borders worse on Spot 10k (basket weave, seed 0:
    where the map jumps 1.52 -> 1.81 times the jump within patches,
    rotation median 7 -> 10 degrees); with the shorter repeat instead
    (bricks 20 px instead of 35) bricks took 14 s CPU on Spot 10k, over the
    10 s budget.
    """
    n = np.linalg.norm(ps.periods, axis=1)
    n_in = n[n <= min(shape[:2]) / 4.0]
    return float(n_in.max() if n_in.size else n.min())


def _rigid_fit(X, Y):
    """Least-squares rotation and translation ``Y ~ R X + t`` of 2D points (k, 2).

    The rotation maximising ``sum y . (R x)`` over the centred points has the
    angle of ``(a + e, b - d)`` for ``[[a, b], [d, e]] = sum x y^T`` (the
    2 x 2 Kabsch solution in closed form: the rotation of the SVD's ``V U^T``).
    Returns ``(R, t)``, or None when the best orthogonal map is a reflection
    (``det < 0``, the SVD's ``V U^T`` has determinant -1) or the points give no
    direction.
    """
    xm, ym = X.mean(axis=0), Y.mean(axis=0)
    (a, b), (d, e) = ((X - xm).T @ (Y - ym)).tolist()
    r = np.hypot(a + e, b - d)
    if not (a * e - b * d > 0 and r > 0):
        return None
    co, si = (a + e) / r, (b - d) / r
    R = np.array([[co, -si], [si, co]])
    return R, ym - R @ xm


def _refine_placement(img, R, t, q, target, angle_step, fast=False):
    """Sub-pixel and sub-grid refinement of a mask placement ``x -> R q + t``.

    The FFT search gives the best placement on the pixel grid and on the
    orientation grid.  Around it, the continuous mask error
    ``E = sum (target - img(R q + t))^2`` (bilinear samples of ``img`` at the
    placed mask points ``q`` (k, 2), colours ``target`` (k, c)) is fitted by a
    parabola in x, in y (steps of half a pixel) and in the angle (steps of
    half the orientation grid, rotating about the mask's centroid), two
    rounds with halved steps; the lowest evaluated placement is kept, so the
    result is never worse than the start.  ``fast``: sample the image with the
    compiled loop (same values).

    Returns
    -------
    R, t : numpy.ndarray, (2, 2) and (2,) float64
    error : float
        ``E`` at the returned placement.
    """
    qc = q.mean(axis=0)

    def place(p):
        c, s = np.cos(p[2]), np.sin(p[2])
        R1 = np.array([[c, s], [-s, c]]) @ R
        return R1, R @ qc + t - R1 @ qc + p[:2]

    def energy(p):
        R1, t1 = place(p)
        d = target - _sample(img, q @ R1.T + t1, fast)
        return float(np.sum(d * d))

    p = np.zeros(3)
    e0 = energy(p)
    steps = np.array([0.5, 0.5, 0.5 * angle_step])
    for _ in range(2):
        for j in range(3):
            h = steps[j]
            em = energy(p - h * np.eye(3)[j])
            ep = energy(p + h * np.eye(3)[j])
            cand = [(e0, 0.0), (em, -h), (ep, h)]
            curv = em - 2.0 * e0 + ep
            if curv > 0:
                x = float(np.clip(0.5 * h * (em - ep) / curv, -h, h))
                if 0.0 < abs(x) < h:
                    cand.append((energy(p + x * np.eye(3)[j]), x))
            e_best, x_best = min(cand, key=lambda z: z[0])
            p[j] += x_best
            e0 = e_best
        steps *= 0.5
    R1, t1 = place(p)
    return R1, t1, e0


def _signed_areas(P: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Twice the signed areas of triangles ``tri`` (t, 3) over positions ``P`` (p, 2)."""
    t = P[tri]
    return (t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1]) \
        - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0])


def _snap(P, target, close, tri):
    """Move the ``close`` rows of ``P`` (in place) onto ``target`` unless that folds a face.

    ``tri`` (t, 3) are the cluster's faces as row indices of ``P``.  On fine
    meshes the snapping distance is a sizeable part of an edge in pixels, and
    snapping both ends of a short edge can reverse or crush a face: the
    vertices of such faces keep their own position (a small crack instead of
    a flipped face).  Returns the rows actually snapped.
    """
    close = close.copy()
    a0 = _signed_areas(P, tri)
    while close.any():                  # every round unsnaps at least one vertex
        trial = P.copy()
        trial[close] = target[close]
        bad = _signed_areas(trial, tri) * np.sign(a0) < 0.3 * np.abs(a0)
        if not bad.any():
            break
        close[np.unique(tri[bad])] = False
    P[close] = target[close]
    return close


def _relax(P, verts, faces, movable, F, st, full, rng, f, fast=False):
    """Local edge relaxation (Fig. 6): greedy random moves of shared border vertices.

    ``P`` (p, 2) full-res positions of ``verts``; ``movable`` marks the shared
    border vertices where the mapping jumps.  For each, the error is the
    squared colour difference between this cluster's and the neighbour's
    texture at samples along the shared edges around it, weighted by the
    vertex's hat function; candidate moves are drawn in a disc of radius
    ``f`` pixels halved at each of three rounds, and the best is kept.
    ``fast``: sample the image with the compiled loop (same values).
    """
    mv = np.flatnonzero(movable)
    if mv.size == 0:
        return P
    n = int(F.max()) + 1
    pos = np.full((n, 2), np.nan)
    pos[verts] = P
    # neighbour positions per vertex (mean over textured corners)
    nb = st.agreed()
    cnt = np.where(np.isnan(nb[:, 0]), 0.0, 1.0)
    # shared edges of the cluster (both ends with a neighbour position)
    e = np.concatenate([F[faces][:, [0, 1]], F[faces][:, [1, 2]], F[faces][:, [2, 0]]])
    e = np.sort(e, axis=1)
    key = np.unique(e[:, 0] * n + e[:, 1])          # = np.unique(e, axis=0), without a
    e = np.stack([key // n, key % n], axis=1)       # structured sort
    both = (cnt[e[:, 0]] > 0) & (cnt[e[:, 1]] > 0)
    e = e[both]
    if e.shape[0] == 0:
        return P
    ts = np.array([0.0, 0.25, 0.5, 0.75])
    vid = verts[mv]
    # per movable vertex: its shared edges, oriented from it
    ea = np.concatenate([e[:, 0], e[:, 1]])
    eb = np.concatenate([e[:, 1], e[:, 0]])
    slot = np.full(n, -1, np.int64)
    slot[vid] = np.arange(vid.size)
    sel = slot[ea] >= 0
    ea, eb, owner = ea[sel], eb[sel], slot[ea[sel]]
    if ea.size == 0:
        return P

    na, nbb = nb[ea], nb[eb]
    y = na[:, None, :] * (1 - ts)[None, :, None] + nbb[:, None, :] * ts[None, :, None]
    target = _sample(full, y.reshape(-1, 2), fast)   # the neighbour's texture along the edges
    b = pos[eb]

    # compiled: three colour channels (the order of np.sum checked for them), no NaN
    jit_err = fast and full.shape[2] == 3 and np.isfinite(b).all() and np.isfinite(target).all()

    def err(cand):                       # cand (k, 2) positions of the movable vertices
        if jit_err and np.isfinite(cand).all():
            return _relax_error_compiled(full, cand, owner, b, target, ts, vid.size)
        a = cand[owner]
        x = a[:, None, :] * (1 - ts)[None, :, None] + b[:, None, :] * ts[None, :, None]
        d = _sample(full, x.reshape(-1, 2), fast) - target
        w = np.broadcast_to((1 - ts)[None, :], x.shape[:2]).ravel()
        per = np.sum(d * d, axis=1) * w
        return np.bincount(np.repeat(owner, ts.size), weights=per, minlength=vid.size)

    cur = pos[vid].copy()
    e0 = err(cur)
    # search radius: the paper's disc, capped by a fifth of the shortest edge at the vertex
    elen = np.linalg.norm(pos[ea] - pos[eb], axis=1)
    short = np.full(vid.size, np.inf)
    np.minimum.at(short, owner, elen)
    ff = F[faces]
    loc = np.searchsorted(verts, ff)
    for a_, b_ in ((0, 1), (1, 2), (2, 0)):
        own = slot[ff[:, a_]]
        ok_ = own >= 0
        np.minimum.at(short, own[ok_], np.linalg.norm(P[loc[ok_, a_]] - P[loc[ok_, b_]], axis=1))
    radius = np.minimum(float(f), RELAX_EDGE_FRACTION * np.where(np.isfinite(short), short, 0.0))

    def areas(posv):
        t = posv[loc]
        return (t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1]) \
            - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0])

    a_before = areas(P)
    if jit_err and np.isfinite(cur).all() and np.isfinite(radius).all():
        # the same draws (one (18, 2, k) block is the 36 calls' stream, in order), the
        # same offsets (numpy's own sqrt, cos, sin of them) and the candidates' errors
        # and greedy updates in one compiled loop
        u = rng.random((3 * 6, 2, vid.size))
        r = (radius * np.array([1.0, 0.5, 0.25]).repeat(6)[:, None]) * np.sqrt(u[:, 0])
        t = u[:, 1] * 2 * np.pi
        off = np.stack([r * np.cos(t), r * np.sin(t)], 2)
        cur = _relax_search_compiled(full, cur, off, owner, b, target, ts, e0)
    else:
        for _ in range(3):
            for _k in range(6):
                r = radius * np.sqrt(rng.random(vid.size))
                t = rng.random(vid.size) * 2 * np.pi
                cand = cur + np.stack([r * np.cos(t), r * np.sin(t)], 1)
                e1 = err(cand)
                better = e1 < e0
                cur[better] = cand[better]
                e0 = np.where(better, e1, e0)
            radius = radius * 0.5
    # undo moves that fold or crush a face of the cluster
    for _ in range(3):
        trial = P.copy()
        trial[mv] = cur
        a_after = areas(trial)
        crushed = (a_after * np.sign(a_before) < 0.3 * np.abs(a_before))
        if not crushed.any():
            break
        back = np.unique(ff[crushed])
        back = back[slot[back] >= 0]
        cur[slot[back]] = P[mv][slot[back]]
    out = P.copy()
    out[mv] = cur
    return out


def _face_groups(FF: np.ndarray, todo: np.ndarray, size: int) -> list:
    """The faces ``todo`` (m,) bool cut into groups of at most ``size`` adjacent faces.

    Connected components of the remaining faces (across shared edges), each
    cut into consecutive runs of its breadth-first order (a run is connected
    or nearly so; the projection flattening does not need more).
    """
    idx = np.flatnonzero(todo)
    if idx.size == 0:
        return []
    slot = np.full(FF.shape[0], -1, np.int64)
    slot[idx] = np.arange(idx.size)
    nb = FF[idx]
    a = np.repeat(np.arange(idx.size), 3)
    b = np.where(nb >= 0, slot[np.maximum(nb, 0)], -1).ravel()
    keep = b >= 0
    G = sp.csr_matrix((np.ones(int(keep.sum())), (a[keep], b[keep])), shape=(idx.size,) * 2)
    ncomp, lab = connected_components(G, directed=False)
    first = np.full(ncomp, -1, np.int64)
    first[lab[::-1]] = np.arange(idx.size)[::-1]
    out = []
    for k in range(ncomp):
        order = breadth_first_order(G, int(first[k]), directed=False,
                                    return_predecessors=False)
        out.extend(idx[order[j:j + size]] for j in range(0, order.size, size))
    return out


def _fill_gaps(V, F, FF, st) -> int:
    """Texture the remaining faces by unfolding them from a textured neighbour."""
    filled = 0
    while not st.done.all():
        todo = np.flatnonzero(~st.done)
        nb = FF[todo]
        ok = (nb >= 0) & st.done[np.maximum(nb, 0)]
        has = ok.any(axis=1)
        if not has.any():
            # a part with no texture at all: give it a flat projection at the origin
            f0 = todo[0]
            st.corner[f0] = 0.0
            st.done[f0] = True
            filled += 1
            continue
        fa = todo[has]
        k = np.argmax(ok[has], axis=1)
        g = nb[has, k]
        a = F[fa, k]
        b = F[fa, (k + 1) % 3]
        c = F[fa, (k + 2) % 3]
        # g's corner positions for a and b
        ga = np.argmax(F[g] == a[:, None], axis=1)
        gb = np.argmax(F[g] == b[:, None], axis=1)
        gc = 3 - ga - gb
        ua, ub, ug = st.corner[g, ga], st.corner[g, gb], st.corner[g, gc]
        pa, pb = V[a], V[b]
        ev = pb - pa
        le = np.linalg.norm(ev, axis=1)
        ex = ev / np.maximum(le, 1e-300)[:, None]
        # coordinates of c and of g's third vertex in the edge frame (s along, t across)
        def st_coords(p):
            d = p - pa
            s = np.sum(d * ex, axis=1)
            t = np.linalg.norm(d - s[:, None] * ex, axis=1)
            return s, t
        sc, tc = st_coords(V[c])
        # texture-space frame from g: along the edge, and toward g's third vertex
        du = ub - ua
        lu = np.linalg.norm(du, axis=1)
        ux = du / np.maximum(lu, 1e-300)[:, None]
        uy = np.stack([-ux[:, 1], ux[:, 0]], 1)
        side = np.sign(np.sum((ug - ua) * uy, axis=1))
        side[side == 0] = 1.0
        k_scale = lu / np.maximum(le, 1e-300)
        uc = ua + (sc * k_scale)[:, None] * ux - (side * tc * k_scale)[:, None] * uy
        st.corner[fa, k] = ua
        st.corner[fa, (k + 1) % 3] = ub
        st.corner[fa, (k + 2) % 3] = uc
        st.done[fa] = True
        filled += fa.size
    return filled





def read_hpm_image(path) -> np.ndarray:
    """Read the texture sample: a grey or RGB(A) picture, as ``(h, w, 3)`` uint8.

    Parameters
    ----------
    path : str or os.PathLike

    Returns
    -------
    numpy.ndarray, (h, w, 3) uint8

    Raises
    ------
    MissingFileError
        If the file does not exist.
    InputError
        If it is not a readable picture, or not grey/RGB (e.g. CMYK, float).
    """
    from pathlib import Path

    p = Path(path)
    if not p.is_file():
        raise MissingFileError(f"{p}: no such image file")
    try:
        with Image.open(p) as im:
            mode = im.mode
    except Exception as exc:  # pillow raises many types for unreadable images
        raise InputError(f"{p}: cannot read the image ({type(exc).__name__}); "
                         "give a PNG or JPEG file") from None
    if mode not in ("1", "L", "LA", "P", "PA", "RGB", "RGBA"):
        raise InputError(f"{p}: the image is {mode}, not 8-bit RGB or grey; convert it to an "
                         "8-bit RGB or grey PNG/JPEG first")
    arr = load_image(p)
    if min(arr.shape[:2]) < 8:
        raise InputError(f"{p}: the image is {arr.shape[1]} x {arr.shape[0]} pixels; give one "
                         "of at least 8 x 8")
    return np.ascontiguousarray(arr[:, :, :3])


def hpm_mesh(V, F, result: HPMResult, image, *, name: str = ""):
    """The textured mesh record: the base with ``result``'s uv and the image itself.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    result : HPMResult
    image : numpy.ndarray, (h, w, 3) uint8
    name : str, optional

    Returns
    -------
    geotex.mesh.record.Mesh
    """
    return Mesh(V, F, uv=result.uv, uv_faces=result.uv_faces,
                texture=np.ascontiguousarray(image[:, :, :3]), name=name,
                metadata={"hpm": result.report()})
