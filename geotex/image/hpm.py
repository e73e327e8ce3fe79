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
   (:mod:`geotex.image.hpm_faces`, :mod:`geotex.image.hpm_kernels`) and the mask
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

Modules: this one holds the public entry point and the coarse-to-fine loop
(:func:`hpm_texture`, whose steps share its state as closures) and re-exports
the rest of the public API; :mod:`geotex.image.hpm_result` (the result, the
split-vertex uv output, the image reader, the mesh record),
:mod:`geotex.image.hpm_state` (the mutable state of a run),
:mod:`geotex.image.hpm_kernels` (compiled sampling, relaxation error and
search, window minima, each beside its helpers),
:mod:`geotex.image.hpm_pattern` (the sample's field and size),
:mod:`geotex.image.hpm_fit` (rigid fits, placement refinement, crack snapping
and relaxation), :mod:`geotex.image.hpm_gaps` (face-level groups, the last
gaps) and :mod:`geotex.image.hpm_faces` (per-fit helpers of the face level).
"""

from __future__ import annotations

import heapq

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from geotex.errors import InputError
from geotex.image.atlas import rasterize_triangles
from geotex.jit import JIT_MIN_SIZE
from geotex.fields.combing import comb_direction_field
from geotex.image.fftmatch import (match_energy, opponent_colors, pattern_scale,
                                   texture_spectra)
from geotex.image.hpm_faces import field_coefficients, textured_band, vertex_faces
from geotex.image.hpm_fit import _refine_placement, _relax, _rigid_fit, _snap
from geotex.image.hpm_gaps import _face_groups, _fill_gaps
from geotex.image.hpm_kernels import _block_mean, _sample, _window_minima
from geotex.image.hpm_pattern import _angle_gap, _pattern_field, _pattern_size, _period_lattice
from geotex.image.hpm_result import (HPMLevel, HPMResult, _median_patch_diameter, _split_uv,
                                     hpm_mesh, read_hpm_image)
from geotex.image.hpm_state import _State
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.geometry import face_areas
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

#: Bases from this many faces up sample the image, rasterize the masks and assemble
#: the matching energies with compiled loops (the same values; ``GEOTEX_JIT_MIN_SIZE``
#: lower than this lowers it).  A mapping of 2000 faces does tens of thousands of
#: lookups; below that, loading numba (~0.4 s once) costs more.
SAMPLE_JIT_FACES = 2000

#: Multiplier that mirrors 2D positions (k, 2) in y: ``P * FLIP_Y`` is ``(x, -y)`` exactly.
FLIP_Y = np.array([1.0, -1.0])

__all__ = ["HPMLevel", "HPMResult", "hpm_texture", "check_hpm_base", "read_hpm_image",
           "hpm_mesh"]


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
        after a quarter turn, see
        :func:`geotex.image.hpm_pattern._pattern_field`) for a periodic or
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
        lattice, basis, shortest = _period_lattice(ps.periods, W_img, H_img)
        stripes = ps.periods.shape[0] == 1
        snap_tol = LATTICE_SNAP * shortest
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
    uv_out, uv_faces = _split_uv(st.corner, F, W_img, H_img)
    if min_patch > 0.0 or (structure and ps.periodic):
        # how many pattern periods the patches span (area-weighted median over the faces of
        # the equivalent-disc diameter of the placement that textured them): below 1 the
        # patches are smaller than the pattern, whose structure is then lost (paper §5.2)
        med = _median_patch_diameter(st.patch, A)
        if med is not None:
            pattern_info["patch_periods"] = med * ppm / _pattern_size(ps, img.shape)
    fl = np.where(st.face_level < 0, L - 1, st.face_level)
    return HPMResult(uv=np.ascontiguousarray(uv_out), uv_faces=uv_faces, patch=st.patch,
                     face_level=fl, levels=levels, pattern=pattern_info)
