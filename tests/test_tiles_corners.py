"""Tile corners are filled: strips run up to the corners without colliding there."""

from __future__ import annotations

import numpy as np
import pytest

from geotex.errors import InputError
from geotex.mesh.primitives import icosphere
from geotex.tiles import build_tileset, check_seams, planar_tiling, random_arrangement
from geotex.tiles.strips import corner_conflicts, element_boxes, lattice_corner
from geotex.tiles.verify import corner_density
from test_tiles import studs


def _bumps(centres, r=0.1):
    V0, F0 = icosphere(1)
    V = np.vstack([V0 * [r, r, 0.1] + [x, y, 0.05] for x, y in centres])
    F = np.vstack([F0 + k * len(V0) for k in range(len(centres))])
    return V, F


def test_corner_density_tells_corners_from_the_rest():
    # a 2 x 2 tiling with bumps only at the 9 grid points: corners full, rest empty
    pts = [(x, y) for x in range(3) for y in range(3)]
    V, F = _bumps(pts)
    d = corner_density(V, F, (2, 2))
    assert d.corner == pytest.approx(4 * np.pi * 0.01 / 1.0, rel=0.1) and d.elsewhere == 0.0
    # bumps only at tile centres: nothing in the corner squares
    V, F = _bumps([(0.5, 0.5), (1.5, 0.5), (0.5, 1.5), (1.5, 1.5)])
    d = corner_density(V, F, (2, 2))
    assert d.corner == 0.0 and d.elsewhere > 0.0 and d.ratio == 0.0
    # parts below the plane do not count
    V2 = V.copy()
    V2[:, 2] -= 1.0
    assert corner_density(V2, F, (2, 2)).elsewhere == 0.0
    with pytest.raises(InputError, match="quarter"):
        corner_density(V, F, (2, 2), quarter=0.6)
    with pytest.raises(InputError, match="grid"):
        corner_density(V, F, (0, 2))


@pytest.fixture(scope="module")
def iso_paste(shared_tileset):
    # the same set as test_tiles.py's paste_iso_set, built once per run
    return shared_tileset("studs-iso-2-seed3-paste", lambda: build_tileset(
        studs(), colors=2, isotropic=True, seed=3, interior="paste"))


def test_corner_squares_hold_as_much_relief_as_the_rest(iso_paste):
    assert check_seams(iso_paste).ok
    V, F = planar_tiling(iso_paste, random_arrangement(iso_paste, 6, 6, seed=0),
                         border="open")
    d = corner_density(V, F, (6, 6))
    assert d.ratio >= 0.85, d


def test_elements_cross_the_sides_close_to_the_corners(iso_paste):
    # elements cross tile sides within 0.1 of a corner (the former corner margin,
    # half the widest element plus a gap, kept them 0.14 away)
    close = 0
    for i in range(len(iso_paste)):
        V, _ = iso_paste.tile(i)
        on_side = (V[:, 1] == 0.0) | (V[:, 1] == 1.0)
        u = V[on_side, 0]
        close += int(((u < 0.1) | (u > 0.9)).any())
    assert close >= len(iso_paste) // 2


def test_strip_ends_never_collide_at_corners():
    from geotex.tiles.build import _exemplar_arrays
    from geotex.tiles.strips import pick_strips

    src = _exemplar_arrays(studs())[0]
    picked, _ = pick_strips(src.V, src.F, src.size, count=2, along=0,
                            rng=np.random.default_rng(3))
    for x in picked:
        for y in picked:
            assert not corner_conflicts(x.corners, y.corners).any()
    # an element and itself turned a quarter collide when it sits at the corner,
    # unless one lies above the other (overlapping scales)
    def fake(z0, z1):
        img = {k: (np.full((1, 80, 80), np.inf), np.full((1, 80, 80), -np.inf)) for k in
               ("above_start", "below_start", "above_far", "below_far")}
        for k in ("above_start", "below_start"):
            img[k][0][0, 2:20, 0:10] = z0
            img[k][1][0, 2:20, 0:10] = z1
        return img

    assert corner_conflicts(fake(0.0, 0.2), fake(0.0, 0.2))[0, 0]
    assert not corner_conflicts(fake(0.0, 0.2), fake(0.3, 0.4))[0, 0]
    assert not corner_conflicts(fake(0.0, 0.2), {k: (v[0][:, ::-1], v[1][:, ::-1]) for k, v
                                                 in fake(0.0, 0.2).items()})[0, 0]


def test_lattice_corner_moves_tile_corners_off_the_sites():
    # diamond lattice (sites on a checkerboard of half pitch): the phase found on
    # a site is moved half a pitch along one axis, between four elements
    p = 0.5
    sites = [(0.25 + 0.25 * i, 0.25 + 0.25 * j) for i in range(12) for j in range(12)
             if (i + j) % 2 == 0]
    V, F = _bumps(sites, r=0.11)
    _, lo, hi = element_boxes(V, F)
    px, py = lattice_corner(lo, hi, p, (0.25, 0.25))
    assert (px, py) in ((0.0, 0.25), (0.25, 0.0))
    centres = np.array(sites)
    corner = np.array([px, py])
    d = np.abs((centres - corner + p / 2) % p - p / 2)
    assert (d.max(axis=1) > 0.11).all()      # no element box holds a tile corner


def _scales():
    from geotex.exemplars import exemplar

    return exemplar("scales", size=(3.0, 3.0), pitch=0.25, length=0.3, row_spacing=0.17,
                    jitter=0.5, resolution=8, seed=0)


def test_fill_corners_fills_empty_corner_squares_and_touches_nothing():
    from geotex.check.intersections import self_intersecting_pairs
    from geotex.mesh.topology import concatenated
    from geotex.tiles.build import _exemplar_arrays
    from geotex.tiles.fill import CLEAR, ExemplarPixels, fill_corners

    src = _exemplar_arrays(_scales())[0]
    # a unit window of overlapping scales with every element reaching into a
    # corner square taken out
    V, F = src.window((1.0, 1.0), (1.0, 1.0))
    _, lo, hi = element_boxes(V, F)
    near = lambda a, b: (a < 0.25) | (b > 0.75)
    corner = near(lo[:, 0], hi[:, 0]) & near(lo[:, 1], hi[:, 1])
    labels = element_boxes(V, F)[0]
    V, F = V, F[~corner[labels]]
    px = ExemplarPixels(src.V, src.F, src.labels, src.lo, src.hi)
    (Va, Fa), count = fill_corners(V, F, px, np.random.default_rng(0))
    assert count > 0
    assert (Va[:, :2] >= CLEAR).all() and (Va[:, :2] <= 1.0 - CLEAR).all()
    both = concatenated([(V, F), (Va, Fa)])
    assert len(self_intersecting_pairs(*both)) == 0
    # the corner squares hold relief again (faces above the plane)
    up = lambda W, G: G[W[G][:, :, 2].mean(axis=1) > 0]
    d_before = corner_density(V, up(V, F), (1, 1))
    d_after = corner_density(*both, (1, 1))
    assert d_after.corner > d_before.corner + 0.1
    # same generator, same elements
    again = fill_corners(V, F, px, np.random.default_rng(0))
    assert again[1] == count and np.array_equal(again[0][0], Va)


def test_strips_that_meet_only_other_classes_keep_their_end_elements():
    # a strip of a non-isotropic set meets strips of the other class at the
    # corners, never itself: it keeps every element crossing its segment
    from geotex.exemplars import exemplar
    from geotex.tiles.build import _exemplar_arrays
    from geotex.tiles.strips import pick_strips

    src = _exemplar_arrays(exemplar("chainmail", size=(3.0, 3.0), seed=0))[0]
    kept = {}
    for own in (True, False):
        (strip,), _ = pick_strips(src.V, src.F, src.size, count=1, along=0,
                                  rng=np.random.default_rng(1), meets_itself=own)
        o = np.asarray(strip.origin)
        t0, t1 = src.lo[:, 0] - o[0], src.hi[:, 0] - o[0]
        s0, s1 = src.lo[:, 1] - o[1], src.hi[:, 1] - o[1]
        crossing = (s0 < -0.005) & (s1 > 0.005) & (t0 >= 0.01) & (t1 <= 0.99)
        kept[own] = (len(strip.boxes), int(crossing.sum()))
        if own:
            assert not corner_conflicts(strip.corners, strip.corners).any()
    assert kept[False][0] == kept[False][1]
    assert kept[True][0] < kept[True][1]      # chain mail rings collide with themselves


@pytest.mark.parametrize("name", ["chainmail", "scales-planar", "scales", "studs",
                                  "studs-complete", "knurl", "knurl-1"])
def test_catalog_corner_squares_are_not_left_empty(name):
    # issue 14 asks for 0.85 (benchmarks/results/tiles_corners.md); the catalog
    # before the corner fill and the exact pruning had chainmail 0.55 and
    # scales-planar 0.63, then 0.70 and 0.84; chainmail, cut from its periodic
    # layout since, reaches 1.03; the directional scales (its 16 ridge-free tiles)
    # 0.87; scales-planar with its corner patch 1.05
    from geotex.tiles import load_named

    tiles = load_named(name)
    V, F = planar_tiling(tiles, random_arrangement(tiles, 6, 6, seed=0), border="open")
    assert corner_density(V, F, (6, 6)).ratio >= (
        0.85 if name in ("chainmail", "scales", "scales-planar") else 0.65)


def test_corner_patch_pieces_meet_bit_for_bit_on_the_two_lines():
    from geotex.tiles.strips import corner_patch

    ex = studs()
    p = corner_patch(ex.vertices, ex.faces.astype(np.int64), ex.size, np.random.default_rng(2))
    P = {k: V for k, (V, F) in p.pieces.items()}
    assert all(len(F) for V, F in p.pieces.values())
    # every piece lies in its quadrant, and neighbouring pieces share their cut
    # vertices exactly (the corner point's vertical line too)
    sx = {"ne": 1, "se": 1, "nw": -1, "sw": -1}
    sy = {"ne": 1, "nw": 1, "se": -1, "sw": -1}
    for k, V in P.items():
        assert (sx[k] * V[:, 0] >= 0).all() and (sy[k] * V[:, 1] >= 0).all()

    def on(V, axis):
        return {tuple(r) for r in V[V[:, axis] == 0.0].tolist()}

    assert on(P["ne"], 0) and on(P["ne"], 0) == on(P["nw"], 0)
    assert on(P["se"], 0) == on(P["sw"], 0)
    assert on(P["ne"], 1) == on(P["se"], 1) and on(P["nw"], 1) == on(P["sw"], 1)


def test_corner_patch_fills_every_corner_with_the_same_elements_seamlessly():
    tiles = build_tileset(studs(), colors=2, planar=True, seed=3, interior="paste",
                          corner_patch=True)
    assert check_seams(tiles).ok
    assert tiles.metadata["recipe"]["corner_patch"] is True
    V, F = planar_tiling(tiles, random_arrangement(tiles, 4, 4, seed=1), border="open")
    # every inner grid point holds the same patch: the vertices around it agree
    around = []
    for x in range(1, 4):
        for y in range(1, 4):
            d = V[:, :2] - [x, y]
            near = np.hypot(d[:, 0], d[:, 1]) < 0.06
            around.append(sorted(map(tuple, np.round(np.c_[d[near], V[near, 2]], 9).tolist())))
    assert len(around[0]) > 20 and all(a == around[0] for a in around)
    # and the corner squares hold as much as the rest (measured 0.41 / 0.41;
    # without the patch this set's corners are fuller than the rest, 0.50 / 0.39)
    V6, F6 = planar_tiling(tiles, random_arrangement(tiles, 6, 6, seed=0), border="open")
    assert 0.85 <= corner_density(V6, F6, (6, 6)).ratio <= 1.15
    with pytest.raises(InputError, match="corner_patch"):
        build_tileset(studs(), colors=2, isotropic=True, seed=3, interior="paste",
                      corner_patch=True)


def test_quilt_best_of_keeps_the_densest_accepted_quilt():
    # the first accepted quilt is the one best_of=1 returns (same draws); with
    # best_of=3 quilting goes on and keeps the densest of the accepted ones
    from geotex.quilting import coverage_fraction
    from geotex.tiles.build import interior_quilt, plan_tileset

    planned = plan_tileset(studs(), colors=1, planar=True, seed=3)
    frame, boxes = planned.plan.frames[0]
    src = planned.plan.src

    def quilted(best_of):
        tile, stats = interior_quilt(src, frame, boxes, np.random.default_rng(5), attempts=6,
                                     best_of=best_of)
        assert tile is not None, stats
        return tile, stats, coverage_fraction(*tile, (0.0, 0.0, 1.0, 1.0), resolution=100)

    first, s1, c1 = quilted(1)
    again, _, _ = quilted(1)
    assert s1["accepted"] == 1
    assert np.array_equal(first[0], again[0]) and np.array_equal(first[1], again[1])
    best, s3, c3 = quilted(3)
    assert 1 < s3["accepted"] <= 3 and s3["attempts"] >= s3["accepted"]
    assert c3 >= c1
    with pytest.raises(InputError, match="quilt_best_of"):
        build_tileset(studs(), colors=1, planar=True, quilt_best_of=0)
    with pytest.raises(InputError, match="quilt_attempts"):
        build_tileset(studs(), colors=1, planar=True, quilt_attempts=True)


def test_corner_patch_of_scales_leaves_no_vertex_next_to_a_cut_line():
    # a vertex within the cut's snap distance of a line is pushed off it and
    # leaves a sliver face on the tile side; the patch centre is nudged so
    # that every vertex is on a line or at least PATCH_SNAP away from it
    from geotex.exemplars import exemplar
    from geotex.tiles.strips import PATCH_SNAP, corner_patch

    ex = exemplar("scales", size=(4.0, 4.0), seed=0)
    for seed in range(3):
        p = corner_patch(ex.vertices, ex.faces.astype(np.int64), ex.size,
                         np.random.default_rng(seed))
        xy = np.abs(np.concatenate([V[:, :2] for V, _ in p.pieces.values()]))
        assert xy[xy != 0.0].min() >= PATCH_SNAP
        assert (xy == 0.0).any(axis=0).all()      # cut vertices on both lines


def test_compiled_place_search_follows_the_height_rule():
    # _first_free gives the first candidate place where heights_touch holds for no
    # placed image: random height images, some overlapping in projection
    from geotex.tiles.fill import CLEAR, _first_free, _packed, heights_touch

    rng = np.random.default_rng(5)

    def image(a, b):
        low = rng.uniform(0.0, 0.3, (a, b))
        high = low + rng.uniform(0.0, 0.2, (a, b))
        gone = rng.random((a, b)) < 0.2                  # absent pixels
        low[gone], high[gone] = np.inf, -np.inf
        return low, high

    placed = [(rng.integers(0, 60, 2), *image(*rng.integers(3, 15, 2))) for _ in range(12)]
    images = _packed(placed)
    low, high = image(6, 9)
    places = rng.integers(-5, 70, (400, 2))
    touches = [any(heights_touch((at, low, high), h, CLEAR) for h in placed) for at in places]
    assert any(touches) and not all(touches)
    start = 0
    free = []
    while (c := _first_free(places, low, high, images, start)) >= 0:
        free.append(c)
        start = c + 1
    assert free == [i for i, t in enumerate(touches) if not t]
    assert _first_free(places, low, high, _packed([]), 0) == 0


def _small_studs():
    from geotex.exemplars import exemplar
    return exemplar("studs", size=(3, 3), pitch=0.25, radius=0.08, jitter=0.3)


def test_corner_merge_merges_corresponding_corner_elements_and_stays_seamless():
    from geotex.quilting import split_elements
    from geotex.tiles.build import plan_tileset
    from geotex.tiles.frame import frame_of, placed_band

    ex = _small_studs()
    tiles = build_tileset(ex, colors=1, isotropic=True, interior="paste", corner_merge=True)
    assert check_seams(tiles).ok
    cm = tiles.metadata["corner_merge"]
    assert tiles.metadata["recipe"]["corner_merge"] is True
    assert cm["merged"] >= 1 and cm["kept_unmerged"] == 0
    assert cm["added"] + cm["merged"] + cm["dropped"] + cm["undone"] >= cm["merged"] + 1
    # the merged frame holds one element per corresponding pair: fewer elements
    # than the crossing halves and band elements placed side by side
    plan = plan_tileset(ex, colors=1, isotropic=True, interior="paste", corner_merge=True)
    sn, we = plan.strips[0], plan.strips[1]
    halves, _ = frame_of((sn, we), (0, 0, 0, 0))
    band = sum(len(split_elements(*placed_band(sn[0], side))) for side in range(4))
    (Vm, Fm), boxes = plan.plan.frames[0]
    merged = len(split_elements(Vm, Fm))
    assert merged == len(split_elements(*halves)) + band - cm["merged"] - cm["dropped"] \
        - cm["undone"]
    assert len(boxes) == merged
    # the side cuts of the frame are those of the halves, bit for bit
    from geotex.tiles.verify import side_boundaries
    for a, b in zip(side_boundaries(*halves)[0], side_boundaries(Vm, Fm)[0]):
        assert np.array_equal(a, b)


def test_corner_merge_options_are_checked():
    with pytest.raises(InputError, match="corner_merge"):
        build_tileset(_small_studs(), colors=2, planar=True, interior="paste",
                      corner_patch=True, corner_merge=True)
    for bad in (0.5, -0.1, "yes"):
        with pytest.raises(InputError, match="corner_merge"):
            build_tileset(_small_studs(), colors=1, isotropic=True, interior="paste",
                          corner_merge=bad)


def test_corner_correspondences_count_boxes_lying_on_each_other_at_a_corner():
    from geotex.tiles.strips import corner_correspondences
    # x: an element beside its line near the start (t 0.1..0.2, s 0.05..0.15);
    # y meets it at the NE quadrant as its below-start image transposed
    x = np.array([[0.1, 0.05, 0.2, 0.15]])
    y = np.array([[0.05, -0.2, 0.15, -0.1]])
    assert corner_correspondences(x, y) == 1
    assert corner_correspondences(x, y + [0.0, -0.1, 0.0, -0.1]) == 0


def test_from_strip_turns_strip_coordinates_back_into_the_exemplar():
    from geotex.tiles.strips import from_strip

    P = np.array([[0.5, 0.25, 0.1], [0.0, -0.5, 0.0]])
    assert from_strip(P, (2.0, 3.0), 0).tolist() == [[2.5, 3.25, 0.1], [2.0, 2.5, 0.0]]
    # along y: t runs up the y axis, s points to -x (a rotation, not a mirror)
    assert from_strip(P, (2.0, 3.0), 1).tolist() == [[1.75, 3.5, 0.1], [2.5, 3.0, 0.0]]
    assert P.tolist() == [[0.5, 0.25, 0.1], [0.0, -0.5, 0.0]]       # input untouched
