"""Geometric Wang tile sets: plane cuts, seams, tilings, files, CLI."""

from __future__ import annotations

import hashlib
from types import SimpleNamespace

import numpy as np
import pytest

from geotex.check import check_mesh
from geotex.cli import main
from geotex.errors import GeotexError, InputError, MeshFileError
from geotex.mesh.primitives import icosphere
from geotex.mesh.topology import edge_topology
from geotex.tiles import (TileSet, build_tileset, check_seams, load_tileset, on_slab,
                          planar_tiling, random_arrangement, save_tileset, tile_count)
from geotex.quilting import closed_element_ok
from geotex.tiles.clip import refined_by_plane, split_by_plane
from geotex.tiles.colors import side_classes
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


@pytest.fixture(scope="module")
def complete_set():
    return build_tileset(studs(), colors=(2, 1, 1), seed=0)


@pytest.fixture(scope="module")
def iso_set():
    return build_tileset(studs(), colors=2, isotropic=True, seed=3)


@pytest.fixture(scope="module")
def paste_iso_set(shared_tileset):
    return shared_tileset("studs-iso-2-seed3-paste", lambda: build_tileset(
        studs(), colors=2, isotropic=True, seed=3, interior="paste"))


# a side as a line: point at parameter t, and the inward direction (into the tile)
_LINES = {0: (lambda t: np.c_[t, 0 * t], (0.0, 1.0)),
          1: (lambda t: np.c_[1 + 0 * t, t], (-1.0, 0.0)),
          2: (lambda t: np.c_[t, 1 + 0 * t], (0.0, -1.0)),
          3: (lambda t: np.c_[0 * t, t], (1.0, 0.0))}


def _side_frame(V, side):
    """(t along the side, d inward from it) of tile points."""
    u, v = V[:, 0], V[:, 1]
    return {0: (u, v), 1: (v, 1.0 - u), 2: (u, 1.0 - v), 3: (v, u)}[side]


def placed_against(V, side_j, side_i):
    """Tile j moved rigidly (no mirror) so that its side ``side_j`` lies on tile i's
    side ``side_i``, outside tile i, running the same way (as on the plane or unfolded
    over a polycube edge)."""
    t, d = _side_frame(V, side_j)
    line, inward = _LINES[side_i]
    P = line(t) - d[:, None] * np.asarray(inward)
    return np.c_[P, V[:, 2]]


def seam_closes(Va, Fa, Vb, Fb, side):
    """Weld two tiles by exact position on tile a's side; True when that side is closed."""
    V = np.vstack([Va, Vb])
    F = np.vstack([Fa, Fb + len(Va)])
    _, inv = np.unique(V, axis=0, return_inverse=True)
    G = inv.ravel()[F]
    topo = edge_topology(G, int(inv.max()) + 1)
    Vu = np.zeros((int(inv.max()) + 1, 3))
    Vu[inv.ravel()] = V
    coord, value = {0: (1, 0.0), 1: (0, 1.0), 2: (1, 1.0), 3: (0, 0.0)}[side]
    e = topo.edges[topo.boundary]
    on = (Vu[e[:, 0], coord] == value) & (Vu[e[:, 1], coord] == value)
    return not on.any() and not topo.non_manifold.any()


def exhaustive_pairs(ts):
    """Every ordered pair of tile sides that may meet (same class and colour, or same
    colour in an isotropic set; one side an "above" half S/E, the other a "below" N/W)."""
    keys = []
    for i in range(len(ts)):
        cls = side_classes(ts.groups[i])
        for s in range(4):
            keys.append((0 if ts.isotropic else int(cls[s]), int(ts.colors[i, s]), i, s))
    for ka in keys:
        for kb in keys:
            if ka[:2] == kb[:2] and ka[3] in (0, 1) and kb[3] in (2, 3):
                yield ka[2], ka[3], kb[2], kb[3]


def physically_seamless(ts):
    count = 0
    for i, si, j, sj in exhaustive_pairs(ts):
        Va, Fa = ts.tile(i)
        Vb, Fb = ts.tile(j)
        if not seam_closes(Va, Fa, placed_against(Vb, sj, si), Fb, si):
            return False, (i, si, j, sj)
        count += 1
    return True, count


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


def test_refined_by_plane_keeps_the_surface_and_its_cut_closes_the_part_below():
    V, F = icosphere(3)
    cut = refined_by_plane(V, F, axis=2, value=0.2345, ordered=True)
    W, G = cut.vertices, cut.faces
    # one surface, refined: closed, consistently oriented, same area, every face on one side
    topo = edge_topology(G, len(W))
    assert not topo.boundary.any() and not topo.inconsistent.any()
    z = W[G, 2]
    assert np.all(z[cut.above] >= 0.2345) and np.all(z[~cut.above] <= 0.2345)
    assert np.all(W[cut.cut.ravel(), 2] == 0.2345) and len(cut.cut) > 0
    # the cut, read as a lid's boundary, runs against the part below: lid + below
    # has no boundary (the lid is a fan around the centre of the cut)
    below = G[~cut.above]
    centre = len(W)
    lid = np.column_stack([cut.cut, np.full(len(cut.cut), centre)])
    Wl = np.vstack([W, W[cut.cut[:, 0]].mean(axis=0)])
    topo = edge_topology(np.vstack([below, lid]), len(Wl))
    assert not topo.boundary.any() and not topo.inconsistent.any()
    # split_by_plane is this refinement, separated
    (Vb, Fb), (Va, Fa) = split_by_plane(V, F, axis=2, value=0.2345, ordered=True)
    assert len(Fb) == (~cut.above).sum() and len(Fa) == cut.above.sum()
    assert np.array_equal(np.sort(Vb[Fb].reshape(-1, 9), axis=0),
                          np.sort(W[below].reshape(-1, 9), axis=0))


def test_planar_set_has_every_colour_combination(planar_set):
    assert len(planar_set) == 16 == tile_count((2, 2, 0), planar=True)
    keys = {tuple(c) for c in planar_set.colors.tolist()}
    assert len(keys) == 16
    assert np.all(planar_set.groups == [0, 1])


def test_complete_set_counts_and_is_seamless(complete_set):
    ts = complete_set
    assert ts.kind == "complete"
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
    # quilted builds are deterministic: same seed, same file bytes
    one = [build_tileset(studs(), colors=1, isotropic=True, seed=s) for s in (7, 7, 8)]
    files = []
    for k, ts in enumerate(one):
        files.append(tmp_path / f"s{k}.npz")
        save_tileset(files[-1], ts)
    digest = [hashlib.sha256(f.read_bytes()).digest() for f in files]
    assert digest[0] == digest[1] != digest[2]
    a = tmp_path / "a.npz"
    save_tileset(a, planar_set)
    back = load_tileset(a)
    assert np.array_equal(back.vertices, planar_set.vertices)
    assert np.array_equal(back.faces, planar_set.faces)
    assert np.array_equal(back.vertex_offsets, planar_set.vertex_offsets)
    assert np.array_equal(back.colors, planar_set.colors)
    assert back.n_colors == planar_set.n_colors and back.name == planar_set.name
    assert back.metadata["recipe"] == planar_set.metadata["recipe"]
    # saving the loaded set again gives the same bytes
    save_tileset(tmp_path / "b.npz", back)
    assert (tmp_path / "b.npz").read_bytes() == a.read_bytes()


def test_corrupted_and_truncated_files_give_clear_errors(tmp_path, planar_set):
    f = tmp_path / "set.npz"
    save_tileset(f, planar_set)
    data = f.read_bytes()
    for k, cut in enumerate((0, 10, len(data) // 3, len(data) // 2, len(data) - 30)):
        (tmp_path / f"cut{k}.npz").write_bytes(data[:cut])
        with pytest.raises(MeshFileError, match="unreadable tile set|not a geotex tile set"):
            load_tileset(tmp_path / f"cut{k}.npz")
    # flipped bytes anywhere: either a clear MeshFileError or (a byte nobody
    # reads, e.g. in a header comment field) the very same set
    rng = np.random.default_rng(0)
    errors = 0
    for k, pos in enumerate(rng.choice(len(data), 40, replace=False)):
        bad = bytearray(data)
        bad[int(pos)] ^= 0x5A
        g = tmp_path / f"bad{k}.npz"
        g.write_bytes(bytes(bad))
        try:
            back = load_tileset(g)
        except MeshFileError as exc:
            assert str(g) in str(exc)
            errors += 1
        else:
            assert np.array_equal(back.vertices, planar_set.vertices)
            assert np.array_equal(back.faces, planar_set.faces)
    assert errors >= 30
    np.savez(tmp_path / "other.npz", x=np.arange(3))
    with pytest.raises(MeshFileError, match="not a geotex tile set"):
        load_tileset(tmp_path / "other.npz")
    (tmp_path / "text.npz").write_text("hello")
    with pytest.raises(MeshFileError, match="unreadable"):
        load_tileset(tmp_path / "text.npz")


def _rewritten(path, tmp_path, name, **changes):
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    arrays.update(changes)
    out = tmp_path / name
    np.savez_compressed(out, **arrays)
    return out


def test_inconsistent_tile_set_files_are_refused(tmp_path, planar_set):
    f = tmp_path / "set.npz"
    save_tileset(f, planar_set)
    with np.load(f) as z:
        vo, faces, colors = z["vertex_offsets"], z["faces"], z["colors"]
        meta = str(z["metadata"])
    cases = {
        "offsets": dict(vertex_offsets=vo[::-1].copy()),
        "outside their tile": dict(faces=faces + 10_000),
        "colours exceed": dict(colors=(colors + 3).astype(np.int8)),
        "not valid JSON": dict(metadata=np.array(meta[:-5])),
        "shapes": dict(groups=np.zeros((3, 2), np.int8)),
    }
    for message, change in cases.items():
        g = _rewritten(f, tmp_path, "x.npz", **change)
        with pytest.raises(MeshFileError, match=message):
            load_tileset(g)


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


# ----------------------------------------------------------------------------
# exhaustive adjacency by actually placing every legal pair side by side


def test_exhaustive_adjacency_planar_and_complete(planar_set, complete_set):
    ok, n = physically_seamless(planar_set)
    assert ok, f"tile sides {n} do not weld shut"
    assert n == 2 * 2 * 8 * 8          # per class, per colour: 8 above x 8 below sides
    ok, n = physically_seamless(complete_set)
    assert ok, f"tile sides {n} do not weld shut"


def test_isotropic_set_contract_and_cross_class_adjacency(iso_set):
    ts = iso_set
    assert len(ts) == 16 == tile_count((2, 2, 2), planar=False, isotropic=True)
    assert ts.isotropic and ts.kind == "isotropic" and not ts.planar
    assert ts.n_colors == (2, 2, 2) and ts.metadata["isotropic"] is True
    assert np.all(ts.groups == [0, 1])
    assert {tuple(c) for c in ts.colors.tolist()} == set(
        __import__("itertools").product(range(2), repeat=4))
    rep = check_seams(ts)
    assert rep.ok, rep.problems[:3]
    # all 64 sides of one colour class: 32 per colour, every ordered pair compared
    assert rep.pairs_checked == 2 * 32 * 31
    # a south side (class X) welds to the east side (class Y) of another tile of
    # the same colour, as across a folded polycube edge
    pairs = list(exhaustive_pairs(ts))
    assert any(si == 0 and sj == 3 for _, si, _, sj in pairs)
    ok, n = physically_seamless(ts)
    assert ok, f"tile sides {n} do not weld shut"
    assert n == 2 * 16 * 16            # per colour: 16 above (S, E) x 16 below (N, W) sides
    # and a plain planar tiling of it is printable
    V, F = planar_tiling(ts, random_arrangement(ts, 3, 3, seed=5))
    assert check_mesh(*on_slab(V, F, (3, 3))).printable


def test_check_seams_compares_across_classes_only_for_isotropic_sets(planar_set):
    # a planar set's X and Y strips differ: fine for a planar set, a seam
    # error once the same tiles claim to be isotropic
    assert check_seams(planar_set).ok
    fake = TileSet(planar_set.vertices, planar_set.faces, planar_set.vertex_offsets,
                   planar_set.face_offsets, planar_set.groups, planar_set.colors, (2, 2, 2),
                   planar_set.height, planar_set.depth, "fake", {"isotropic": True})
    assert fake.isotropic
    rep = check_seams(fake)
    assert not rep.ok and "share colour" in rep.problems[0]
    ok, where = physically_seamless(fake)
    assert not ok
    # old files without the flag are not isotropic
    assert not planar_set.isotropic and planar_set.kind == "planar"


def test_quilted_interiors_keep_side_vertices_bit_exact_and_elements_closed(
        iso_set, paste_iso_set):
    # the same seed draws the same strips; quilting only changes the interior
    assert iso_set.metadata["paste_fallbacks"] == 0
    assert iso_set.metadata["recipe"]["interior"] == "quilt"
    differ = 0
    for i in range(len(iso_set)):
        Vq, Fq = iso_set.tile(i)
        Vp, Fp = paste_iso_set.tile(i)
        sq, stray = side_boundaries(Vq, Fq)
        sp, _ = side_boundaries(Vp, Fp)
        assert stray == 0
        for a, b in zip(sq, sp):
            assert np.array_equal(a, b)
        for coord in (0, 1):
            for value in (0.0, 1.0):
                on_q = {tuple(p) for p in Vq[Vq[:, coord] == value]}
                on_p = {tuple(p) for p in Vp[Vp[:, coord] == value]}
                assert on_q == on_p and on_q
        differ += not (len(Vq) == len(Vp) and np.array_equal(Vq, Vp))
        # every element that touches no side is a closed valid solid
        from geotex.quilting import split_elements
        for e in split_elements(Vq, Fq):
            on_side = ((e.V[:, :2] == 0.0) | (e.V[:, :2] == 1.0)).any()
            if not on_side:
                assert closed_element_ok(e.V, e.F) == ""
            assert e.V[:, :2].min() >= 0 and e.V[:, :2].max() <= 1
    assert differ == len(iso_set)     # quilting made every interior its own
    # a stud copy is either the same stud as the one it overlaps (absorbed) or
    # a different one (dropped): none is fused with its neighbour into a
    # two-bump element (before the correspondence test, 10+ merges per set,
    # with normal jumps of 130-180 degrees at their seams)
    assert iso_set.metadata["merged_elements"] == 0
    assert "stitched_seams" not in iso_set.metadata


def test_quilted_tiling_is_watertight_and_printable(iso_set):
    a = random_arrangement(iso_set, 4, 4, seed=11)
    V, F = planar_tiling(iso_set, a)
    rep = check_mesh(V, F)
    assert rep.printable, rep.reasons
    assert check_mesh(*on_slab(V, F, (4, 4))).printable


def test_lattice_option_needs_a_pitch_dividing_the_tile():
    ex = studs()                         # pitch 0.34: not a divisor of 1
    ex.params = {"pitch": 0.34}
    with pytest.raises(InputError, match="lattice"):
        build_tileset(ex, colors=1, isotropic=True, lattice=True)
    ex = studs(size=(2.0, 2.0), pitch=0.25)
    ex.params = {"pitch": 0.25}
    ts = build_tileset(ex, colors=1, isotropic=True, lattice=True, seed=1)
    assert check_seams(ts).ok and ts.metadata["lattice"][0] == 0.25


def test_isotropic_argument_errors():
    with pytest.raises(InputError, match="isotropic"):
        build_tileset(studs(), colors="2,1,1", isotropic=True)
    with pytest.raises(InputError, match="planar"):
        build_tileset(studs(), colors=2, isotropic=True, planar=True)


def test_cli_build_isotropic_and_list(tmp_path, capsys):
    out = tmp_path / "iso.npz"
    assert main(["tiles", "build", "studs", "-o", str(out), "--colors", "1", "--isotropic",
                 "--interior", "paste"]) == 0
    msg = capsys.readouterr().out
    assert "isotropic set, 1 tiles" in msg
    ts = load_tileset(out)
    assert ts.isotropic and len(ts) == 1 and ts.metadata["recipe"]["interior"] == "paste"
    assert main(["tiles", "check", str(out)]) == 0
    assert main(["tiles", "build", "studs", "-o", str(tmp_path / "x.npz"), "--colors",
                 "2,1,1", "--isotropic"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("geotex: error:") and err.count("\n") == 1
    assert not (tmp_path / "x.npz").exists()
    assert main(["tiles", "build", "studs", "-o", str(tmp_path / "y.npz"), "--interior",
                 "magic"]) == 2
    assert not (tmp_path / "y.npz").exists()


def test_tiles_are_independent_of_build_order():
    # every tile draws from its own generator: built last-to-first, the set is the same
    def backwards(function, plan, n):
        return ((t, function(plan, t)) for t in reversed(range(n)))

    ex = studs()
    a = build_tileset(ex, colors="2,1,1", planar=True, interior="paste", seed=3)
    b = build_tileset(ex, colors="2,1,1", planar=True, interior="paste", seed=3,
                      map_tiles=backwards)
    assert len(a) == 4
    for i in range(len(a)):
        (Va, Fa), (Vb, Fb) = a.tile(i), b.tile(i)
        assert np.array_equal(Va, Vb) and np.array_equal(Fa, Fb)
    assert a.metadata == b.metadata
    with pytest.raises(GeotexError, match="map_tiles"):
        build_tileset(ex, colors="2,1,1", planar=True, interior="paste",
                      map_tiles=lambda f, p, n: iter([(0, f(p, 0))]))


def test_cli_build_on_two_dask_workers_is_byte_identical(tmp_path, capsys, monkeypatch):
    pytest.importorskip("distributed")
    import importlib

    engine = importlib.import_module("geotex.batch.run")   # the module, not batch.run()

    used = []

    def counted(function, plan, n, **kw):
        used.append(kw.get("workers"))
        for t, result in engine_map(function, plan, n, **kw):
            used.append(t)
            yield t, result

    engine_map = engine.map_tasks
    monkeypatch.setattr(engine, "map_tasks", counted)
    args = ["tiles", "build", "studs", "--colors", "2,1,1", "--planar", "--seed", "2"]
    seq, par = tmp_path / "seq.npz", tmp_path / "par.npz"
    assert main(args + ["-o", str(seq), "--workers", "0"]) == 0
    assert main(args + ["-o", str(par), "--workers", "2"]) == 0
    assert "planar set, 4 tiles" in capsys.readouterr().out
    assert used[0] == 2 and sorted(used[1:]) == [0, 1, 2, 3]   # the tiles ran on Dask
    assert seq.read_bytes() == par.read_bytes()
    assert main(args + ["-o", str(tmp_path / "bad.npz"), "--workers", "-1"]) == 2
    assert main(args + ["-o", str(tmp_path / "bad.npz"), "--scheduler", "localhost"]) == 2
    assert main(args + ["-o", str(tmp_path / "bad.npz"), "--workers", "2",
                        "--scheduler", "tcp://localhost:1"]) == 2
    err = capsys.readouterr().err
    assert err.count("geotex: error:") == 3 and "--workers" in err and "--scheduler" in err
    assert not (tmp_path / "bad.npz").exists()


def test_chainmail_tiling_is_written_printable(tmp_path):
    """The shipped chain mail's 6 x 6 tiling (seed 0) was refused: rings grazing the slab
    left needle triangles that float32 rounding folded (8 crossing pairs). The slab union
    now removes needles and the command judges the rounded solid, as the main job does.
    Since the set is linked mail (issue 14) every ring is united with the slab: one body."""
    from geotex.io import read_mesh

    out = tmp_path / "chainmail.stl"
    assert main(["tiles", "tile", "chainmail", "--grid", "6", "6", "--seed", "0",
                 "-o", str(out)]) == 0
    m = read_mesh(out)
    rep = check_mesh(m.vertices, m.faces)
    assert rep.printable and rep.components == 1
