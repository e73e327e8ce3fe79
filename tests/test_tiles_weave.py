"""The weave tile set: plain-weave strands running across tile sides (issue 14)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from geotex.check import check_mesh
from geotex.check.intersections import self_intersecting_pairs
from geotex.cli import main
from geotex.errors import InputError
from geotex.exemplars import exemplar
from geotex.exemplars.weave import GAP, crossing_clearance, strand_geometry
from geotex.io import read_mesh
from geotex.mesh.topology import edge_topology, face_components
from geotex.tiles import build_tileset, check_seams, load_named, planar_tiling, random_arrangement
from geotex.tiles.periodic import WeaveLayout
from geotex.tiles.tileset import save_tileset
from geotex.tiles.verify import corner_density, side_boundaries

PARAMS = dict(pitch=0.5, width=0.36, thickness=0.07, height=0.16, depth=0.05, jitter=0.5,
              resolution=8)


@pytest.fixture(scope="module")
def weave():
    return build_tileset(exemplar("weave", size=(2.0, 2.0), **PARAMS), colors=2,
                         isotropic=True, interior="periodic", seed=2)


def _surface_samples(V, F, per_face=6, seed=0):
    rng = np.random.default_rng(seed)
    r = rng.uniform(size=(len(F), per_face, 2))
    flip = r.sum(axis=2) > 1
    r[flip] = 1 - r[flip]
    P = V[F]
    return (P[:, None, 0] + r[..., :1] * (P[:, None, 1] - P[:, None, 0])
            + r[..., 1:] * (P[:, None, 2] - P[:, None, 0])).reshape(-1, 3)


def test_weave_set_is_seamless_isotropic_and_deterministic(weave, tmp_path):
    assert weave.isotropic and len(weave) == 16 and weave.n_colors == (2, 2, 2)
    rep = check_seams(weave)
    assert rep.ok, rep.problems[:3]
    meta = weave.metadata
    assert meta["periodic"]["layout"] == "plain weave"
    assert meta["periodic"]["strands_per_axis"] == 2 and meta["tiling_border"] == "cap"
    # a side of one colour carries the same strand ends on all four sides, bit for bit:
    # two ellipses per side (one per strand crossing it), nothing else open
    V, F = weave.tile(int(np.flatnonzero((weave.colors == 0).all(axis=1))[0]))
    sides, stray = side_boundaries(V, F)
    S, E, N, W = sides
    assert stray == 0 and len(S) == 2 * PARAMS["resolution"]
    assert np.array_equal(S, W) and np.array_equal(S, N) and np.array_equal(S, E)
    # the two colours differ (their strands sit at other offsets)
    V1, F1 = weave.tile(int(np.flatnonzero((weave.colors == 1).all(axis=1))[0]))
    assert not np.array_equal(side_boundaries(V1, F1)[0][0], S)
    again = build_tileset(exemplar("weave", size=(2.0, 2.0), **PARAMS), colors=2,
                          isotropic=True, interior="periodic", seed=2)
    save_tileset(tmp_path / "a.npz", weave)
    save_tileset(tmp_path / "b.npz", again)
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()
    assert len({weave.tile(t)[0].tobytes() for t in range(len(weave))}) == 16


def test_strands_run_across_the_tiling_over_and_under_and_never_touch(weave):
    V, F = planar_tiling(weave, random_arrangement(weave, 3, 3, seed=1), border="open")
    topo = edge_topology(F, len(V))
    assert not topo.non_manifold.any()
    n, label = face_components(F, len(V))
    # 2 strands per axis and tile: 6 along x and 6 along y, each welded across
    # the 3 tiles it passes (one piece from border to border)
    assert n == 12
    spans = np.array([np.ptp(V[np.unique(F[label == c])][:, :2], axis=0) for c in range(n)])
    assert (spans.max(axis=1) == 3.0).all()
    along_x = spans[:, 0] == 3.0
    assert along_x.sum() == 6
    # over-under: at every crossing the strand on top alternates along each strand
    Vc = [V[np.unique(F[label == c])] for c in range(n)]
    centre = [P[:, 1].mean() if ax else P[:, 0].mean() for P, ax in zip(Vc, along_x)]
    for c in np.flatnonzero(along_x):
        tops = []
        for d in np.flatnonzero(~along_x):
            P, Q = Vc[c], Vc[d]
            near_p = P[np.abs(P[:, 0] - centre[d]) < 0.02]
            near_q = Q[np.abs(Q[:, 1] - centre[c]) < 0.02]
            tops.append(near_p[:, 2].max() > near_q[:, 2].max())
        tops = np.array(tops)[np.argsort([centre[d] for d in np.flatnonzero(~along_x)])]
        assert (tops[1:] != tops[:-1]).all()
    # no two strands intersect, and they keep a clearance (sampled surfaces)
    assert self_intersecting_pairs(V, F).shape[0] == 0
    P = _surface_samples(V, F)
    lab = np.repeat(label, 6)
    gaps = []
    for c in range(n):
        d, _ = cKDTree(P[lab != c]).query(P[lab == c])
        gaps.append(d.min())
    assert min(gaps) > GAP


def test_capped_tiling_is_one_printable_body(tmp_path):
    out = tmp_path / "weave.stl"
    assert main(["tiles", "tile", "weave", "--grid", "3", "3", "--seed", "0",
                 "-o", str(out)]) == 0
    m = read_mesh(out)
    rep = check_mesh(m.vertices, m.faces)
    assert rep.printable and rep.components == 1
    # the strands were kept (capped at the border), not dropped: the relief is
    # well above the slab everywhere
    assert m.vertices[:, 2].max() > 1.5
    tiles = load_named("weave")
    V, F = planar_tiling(tiles, random_arrangement(tiles, 3, 3, seed=0))
    assert not edge_topology(F, len(V)).boundary.size
    assert face_components(F, len(V))[0] == 12
    Vd, Fd = planar_tiling(tiles, random_arrangement(tiles, 3, 3, seed=0), border="drop")
    assert len(Fd) == 0                 # every strand reaches the border


def test_weave_corner_squares_are_as_dense_as_elsewhere():
    tiles = load_named("weave")
    V, F = planar_tiling(tiles, random_arrangement(tiles, 6, 6, seed=0), border="open")
    assert corner_density(V, F, (6, 6)).ratio >= 0.85


def test_weave_layout_refuses_what_it_cannot_build():
    with pytest.raises(InputError, match="touch"):
        WeaveLayout({**PARAMS, "thickness": 0.16})
    with pytest.raises(InputError, match="gap"):
        WeaveLayout({**PARAMS, "width": 0.5})
    with pytest.raises(InputError, match="crossing strands come"):
        WeaveLayout({**PARAMS, "pitch": 0.3, "width": 0.18, "height": 0.12})
    lay = WeaveLayout({**PARAMS, "pitch": 0.3, "width": 0.18})        # 1 / 0.3 -> 4 strands
    assert lay.n == 4 and lay.pitch == 0.25
    geom = strand_geometry(PARAMS)
    assert crossing_clearance(geom, 0.5, 0.0) > crossing_clearance(geom, 0.5, 0.06) > 0
