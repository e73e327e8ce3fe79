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
def iso_paste():
    return build_tileset(studs(), colors=2, isotropic=True, seed=3, interior="paste")


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
