"""Tile sets cut from a periodic layout: linked chain mail (issue 14)."""

from __future__ import annotations

import numpy as np
import pytest

from geotex.check.intersections import self_intersecting_pairs
from geotex.cli import main
from geotex.errors import InputError
from geotex.exemplars import exemplar
from geotex.exemplars.chainmail import diagonal_layout, ring_meshes
from geotex.mesh.topology import edge_topology, face_components
from geotex.tiles import build_tileset, check_seams, planar_tiling, random_arrangement
from geotex.tiles.periodic import PeriodicLayout
from geotex.tiles.tileset import save_tileset
from geotex.tiles.verify import corner_density, side_boundaries

PARAMS = dict(radius=0.28, wire=0.08, depth=0.12, jitter=0.5, resolution=16)


@pytest.fixture(scope="module")
def mail():
    return build_tileset(exemplar("chainmail", size=(2.0, 2.0), **PARAMS), colors=2,
                         isotropic=True, interior="periodic", seed=1)


def _linking(A, B):
    """Gauss linking number of two closed polygons (k, 3), (l, 3)."""
    dA, dB = np.roll(A, -1, 0) - A, np.roll(B, -1, 0) - B
    r = (A + dA / 2)[:, None] - (B + dB / 2)[None]
    cr = np.cross(dA[:, None], dB[None])
    return np.sum(np.einsum("ijk,ijk->ij", r, cr) / np.linalg.norm(r, axis=2) ** 3) / (4 * np.pi)


def test_diagonal_layout_is_periodic_and_its_own_mirror_image():
    pq, C, sign = diagonal_layout(2, 0.0, -1.0, 2.0)
    rows = {tuple(c): s for c, s in zip(C.tolist(), sign.tolist())}
    inside = [(c, s) for c, s in rows.items() if 0 <= c[0] < 1 and 0 <= c[1] < 1]
    assert len(inside) == 8                        # 2 n^2 rings per tile
    for (x, y), s in inside:
        assert rows[(y, x)] == s                    # mirror across x = y
        assert rows[(x + 1, y)] == s and rows[(x, y + 1)] == s
    with pytest.raises(InputError, match="even"):
        diagonal_layout(3, 0.0, 0.0, 1.0)


def test_every_ring_links_its_four_neighbours_and_no_other():
    lay = PeriodicLayout(PARAMS)
    _, C, sign = diagonal_layout(lay.n, lay.offset, -1.0, 2.0)
    C = lay.jittered(C, np.random.default_rng(0))          # the largest shifts allowed
    k = PARAMS["resolution"]
    V, _ = ring_meshes(C, sign, **lay.params)
    centre = V.reshape(len(C), k, -1, 3).mean(axis=2)      # ring centre lines
    middle = np.flatnonzero((np.abs(C - 0.5) < 0.5).all(axis=1))
    assert len(middle) == 8
    for e in middle:
        links = np.array([abs(_linking(centre[e], centre[j])) for j in range(len(C)) if j != e])
        assert (links > 0.9).sum() == 4 and ((links < 0.1) | (links > 0.9)).all()


def test_periodic_set_is_seamless_isotropic_and_deterministic(mail, tmp_path):
    assert mail.isotropic and len(mail) == 16 and mail.n_colors == (2, 2, 2)
    rep = check_seams(mail)
    assert rep.ok, rep.problems[:3]
    meta = mail.metadata
    assert meta["recipe"]["interior"] == "periodic" and meta["periodic"]["rings_per_tile"] == 8
    # a side of one colour carries the same cut on all four sides, bit for bit
    V, F = mail.tile(int(np.flatnonzero((mail.colors == 0).all(axis=1))[0]))
    S, E, N, W = side_boundaries(V, F)[0]
    assert len(S) > 0 and np.array_equal(S, W) and np.array_equal(S, N)
    again = build_tileset(exemplar("chainmail", size=(2.0, 2.0), **PARAMS), colors=2,
                          isotropic=True, interior="periodic", seed=1)
    save_tileset(tmp_path / "a.npz", mail)
    save_tileset(tmp_path / "b.npz", again)
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()
    # the interiors differ from tile to tile (their own small ring shifts)
    assert len({mail.tile(t)[0].tobytes() for t in range(len(mail))}) == 16


def test_tiled_rings_close_across_sides_and_never_cross(mail):
    V, F = planar_tiling(mail, random_arrangement(mail, 3, 3, seed=0))
    topo = edge_topology(F, len(V))
    assert not topo.boundary.any() and not topo.non_manifold.any()
    n, label = face_components(F, len(V))
    # every welded piece is a whole ring (a torus: V - E + F = 0), pieces from
    # up to four tiles joined; a 3 x 3 tiling holds 72 ring sites, minus those
    # cut by the outer border
    for c in range(n):
        f = F[label == c]
        assert len(np.unique(f)) - len(edge_topology(f, len(V)).edges) + len(f) == 0
    assert 50 <= n <= 72
    assert self_intersecting_pairs(V, F).shape[0] == 0
    Vo, Fo = planar_tiling(mail, random_arrangement(mail, 6, 6, seed=0), border="open")
    assert corner_density(Vo, Fo, (6, 6)).ratio >= 0.85


def test_periodic_interior_refuses_what_it_cannot_build(tmp_path, capsys):
    ex = exemplar("chainmail", size=(2.0, 2.0), **PARAMS)
    with pytest.raises(InputError, match="isotropic"):
        build_tileset(ex, colors=2, interior="periodic")
    with pytest.raises(InputError, match="periodic"):
        build_tileset(exemplar("studs", size=(2.0, 2.0)), colors=2, isotropic=True,
                      interior="periodic")
    with pytest.raises(InputError, match="even"):
        build_tileset(exemplar("chainmail", size=(2.0, 2.0), **{**PARAMS, "resolution": 15}),
                      colors=2, isotropic=True, interior="periodic")
    with pytest.raises(InputError, match="too thick"):
        build_tileset(exemplar("chainmail", size=(2.0, 2.0), **{**PARAMS, "wire": 0.13}),
                      colors=2, isotropic=True, interior="periodic")
    out = tmp_path / "m.npz"
    assert main(["tiles", "build", "chainmail", "-o", str(out), "--interior", "periodic",
                 "--colors", "1", "--isotropic"]) == 0
    assert "isotropic set, 1 tiles" in capsys.readouterr().out
    bad = tmp_path / "bad.npz"
    assert main(["tiles", "build", "chainmail", "-o", str(bad), "--interior", "periodic"]) != 0
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "isotropic" in err and not bad.exists()


def test_ordered_cut_gives_mirror_image_vertices_whatever_the_numbering():
    from geotex.mesh.primitives import icosphere
    from geotex.tiles.clip import split_by_plane

    V, F = icosphere(2)
    V = V * [0.3, 0.2, 0.1] + [0.05, 0.013, 0.0]
    order = np.random.default_rng(0).permutation(len(V))      # another numbering
    inverse = np.argsort(order)
    M = V[order][:, [1, 0, 2]]                                # mirrored across x = y
    G = inverse[F][:, ::-1]
    for part in (0, 1):
        a = split_by_plane(V, F, axis=0, value=0.0, ordered=True)[part][0]
        b = split_by_plane(M, G, axis=1, value=0.0, ordered=True)[part][0]
        ca = a[a[:, 0] == 0.0]
        cb = b[b[:, 1] == 0.0][:, [1, 0, 2]]
        assert len(ca) > 10
        assert np.array_equal(ca[np.lexsort(ca.T)], cb[np.lexsort(cb.T)])
