"""Geometric Wang tile sets: plane cuts, seams, tilings, files, CLI."""

from __future__ import annotations

import hashlib
from types import SimpleNamespace

import numpy as np
import pytest

from geotex.check import check_mesh
from geotex.cli import main
from geotex.errors import InputError, MeshFileError
from geotex.mesh.primitives import icosphere
from geotex.mesh.topology import edge_topology
from geotex.tiles import (TileSet, build_tileset, check_seams, load_tileset, on_slab,
                          planar_tiling, random_arrangement, save_tileset, tile_count)
from geotex.tiles.clip import split_by_plane
from geotex.tiles.verify import side_boundaries


def studs(size=(3.0, 3.0), pitch=0.34, seed=0):
    """Squashed spheres on a jittered grid: a tiny exemplar made here."""
    rng = np.random.default_rng(seed)
    V0, F0 = icosphere(1)
    xs = np.arange(pitch / 2, size[0] - pitch / 2 + 1e-9, pitch)
    ys = np.arange(pitch / 2, size[1] - pitch / 2 + 1e-9, pitch)
    C = np.array([(x, y) for y in ys for x in xs]) + rng.uniform(-0.03, 0.03, (len(xs) * len(ys), 2))
    r = rng.uniform(0.09, 0.12, len(C))
    V = np.vstack([V0 * [ri, ri, 0.125] + [x, y, 0.075] for (x, y), ri in zip(C, r)])
    F = np.vstack([F0 + k * len(V0) for k in range(len(C))])
    return SimpleNamespace(vertices=V, faces=F, size=size, height=0.2, depth=0.05,
                           name="studs-test", params={"seed": seed})


@pytest.fixture(scope="module")
def planar_set():
    return build_tileset(studs(), colors=2, planar=True, seed=3)


def test_split_by_plane_halves_share_their_cut_and_weld_shut():
    V, F = icosphere(3)
    (Vb, Fb), (Va, Fa) = split_by_plane(V, F, axis=0, value=0.1234)
    for W, G in ((Vb, Fb), (Va, Fa)):
        topo = edge_topology(G, len(W))
        on_plane = W[topo.edges[topo.boundary].ravel(), 0]
        assert np.all(on_plane == 0.1234)
        assert not topo.non_manifold.any()
    assert Vb[:, 0].max() == 0.1234 and Va[:, 0].min() == 0.1234
    X = np.vstack([Vb, Va])
    _, inv = np.unique(X, axis=0, return_inverse=True)
    G = inv.ravel()[np.vstack([Fb, Fa + len(Vb)])]
    topo = edge_topology(G, int(inv.max()) + 1)
    assert not topo.boundary.any() and not topo.inconsistent.any()
    # area is conserved by the cut
    def area(W, G):
        return 0.5 * np.linalg.norm(np.cross(W[G[:, 1]] - W[G[:, 0]], W[G[:, 2]] - W[G[:, 0]]),
                                    axis=1).sum()
    assert area(Vb, Fb) + area(Va, Fa) == pytest.approx(area(V, F), rel=1e-12)


def test_planar_set_has_every_colour_combination(planar_set):
    assert len(planar_set) == 16 == tile_count((2, 2, 0), planar=True)
    keys = {tuple(c) for c in planar_set.colors.tolist()}
    assert len(keys) == 16
    assert np.all(planar_set.groups == [0, 1])


def test_complete_set_counts_and_is_seamless():
    ts = build_tileset(studs(), colors=(2, 1, 1), seed=0)
    assert len(ts) == 2 * (4 * 1 + 4 * 1 + 1 * 1) == tile_count((2, 1, 1), planar=False)
    rep = check_seams(ts)
    assert rep.ok, rep.problems[:3]
    assert rep.pairs_checked > 0


def test_seams_are_exhaustively_checked_and_a_broken_tile_is_named(planar_set):
    assert check_seams(planar_set).ok
    # move one cut vertex of tile 5's east side: the check must name tile 5
    V = planar_set.vertices.copy()
    v0, v1 = planar_set.vertex_offsets[5], planar_set.vertex_offsets[6]
    east = np.flatnonzero(V[v0:v1, 0] == 1.0)
    assert east.size
    V[v0 + east[0], 2] += 0.01
    broken = TileSet(V, planar_set.faces, planar_set.vertex_offsets, planar_set.face_offsets,
                     planar_set.groups, planar_set.colors, planar_set.n_colors,
                     planar_set.height, planar_set.depth, "broken")
    rep = check_seams(broken)
    assert not rep.ok
    assert any("5 (east)" in p or "5" in p.split("and")[1] for p in rep.problems)


def test_every_tile_is_open_only_along_its_sides(planar_set):
    for i in range(len(planar_set)):
        V, F = planar_set.tile(i)
        sides, stray = side_boundaries(V, F)
        assert stray == 0
        assert sum(len(s) for s in sides) > 0
        assert V[:, 0].min() >= 0 and V[:, 0].max() <= 1
        assert V[:, 1].min() >= 0 and V[:, 1].max() <= 1


def test_welded_tiling_is_watertight_and_printable_on_a_slab(planar_set):
    arrangement = random_arrangement(planar_set, 4, 3, seed=1)
    assert arrangement.shape == (3, 4)
    V, F = planar_tiling(planar_set, arrangement, border="open")
    topo = edge_topology(F, len(V))
    # the only open edges are on the outer border of the tiling
    b = V[topo.edges[topo.boundary].ravel()]
    on_border = np.isclose(b[:, 0], 0) | np.isclose(b[:, 0], 4) | np.isclose(b[:, 1], 0) | \
        np.isclose(b[:, 1], 3)
    assert on_border.all()
    V, F = planar_tiling(planar_set, arrangement)
    rep = check_mesh(V, F)
    assert rep.printable, rep.reasons
    assert check_mesh(*on_slab(V, F, (4, 3))).printable


def test_neighbours_in_a_tiling_agree_on_colours(planar_set):
    a = random_arrangement(planar_set, 5, 5, seed=2)
    c = planar_set.colors[a]                      # (h, w, 4)
    assert np.all(c[:, :-1, 1] == c[:, 1:, 3])    # east == west of the right neighbour
    assert np.all(c[:-1, :, 2] == c[1:, :, 0])    # north == south of the one above


def test_same_seed_same_bytes_and_file_round_trip(tmp_path, planar_set):
    again = build_tileset(studs(), colors=2, planar=True, seed=3)
    a, b = tmp_path / "a.npz", tmp_path / "b.npz"
    save_tileset(a, planar_set)
    save_tileset(b, again)
    assert hashlib.sha256(a.read_bytes()).digest() == hashlib.sha256(b.read_bytes()).digest()
    back = load_tileset(a)
    assert np.array_equal(back.vertices, planar_set.vertices)
    assert np.array_equal(back.faces, planar_set.faces)
    assert back.n_colors == planar_set.n_colors and back.name == planar_set.name
    other = build_tileset(studs(), colors=2, planar=True, seed=4)
    assert not np.array_equal(other.vertices, planar_set.vertices)


def test_corrupted_and_truncated_files_give_clear_errors(tmp_path, planar_set):
    f = tmp_path / "set.npz"
    save_tileset(f, planar_set)
    data = f.read_bytes()
    (tmp_path / "cut.npz").write_bytes(data[: len(data) // 2])
    with pytest.raises(MeshFileError, match="unreadable tile set"):
        load_tileset(tmp_path / "cut.npz")
    bad = bytearray(data)
    bad[len(bad) // 3] ^= 0xFF
    (tmp_path / "bad.npz").write_bytes(bytes(bad))
    with pytest.raises(MeshFileError):
        load_tileset(tmp_path / "bad.npz")
    np.savez(tmp_path / "other.npz", x=np.arange(3))
    with pytest.raises(MeshFileError, match="not a geotex tile set"):
        load_tileset(tmp_path / "other.npz")


def test_bad_build_arguments():
    with pytest.raises(InputError, match="colors"):
        build_tileset(studs(), colors="2,x")
    with pytest.raises(InputError, match="interior"):
        build_tileset(studs(), interior="magic")
    small = studs()
    huge = SimpleNamespace(vertices=small.vertices * [4.0, 4.0, 1.0], faces=small.faces,
                           size=(12.0, 12.0), depth=0.05, name="huge", params={})
    with pytest.raises(InputError, match="wide"):
        build_tileset(huge, colors=1)


def test_cli_check_tile_and_errors(tmp_path, planar_set, capsys):
    f = tmp_path / "set.npz"
    save_tileset(f, planar_set)
    assert main(["tiles", "check", str(f)]) == 0
    assert "seamless" in capsys.readouterr().out
    out = tmp_path / "tiling.stl"
    assert main(["tiles", "tile", str(f), "--grid", "3", "2", "-o", str(out)]) == 0
    assert out.stat().st_size > 1000
    assert main(["tiles", "check", str(tmp_path / "missing.npz")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no such tile set" in err
    assert main(["tiles", "tile", str(f), "--grid", "0", "2", "-o",
                 str(tmp_path / "x.stl")]) == 2
    assert not (tmp_path / "x.stl").exists()
    assert main(["tiles", "tile", str(f), "--grid", "2", "2", "-o", str(f)]) == 2
    assert load_tileset(f).name == planar_set.name
