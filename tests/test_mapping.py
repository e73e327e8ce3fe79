"""Tile sets over shells: identity on flat quads, welding, union, determinism, CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

from geotex.check import check_mesh
from geotex.cli import main
from geotex.errors import InputError
from geotex.exemplars import exemplar
from geotex.io import read_mesh, write_mesh
from geotex.mapping import (edge_colors, mapped_tiles, textured_solid, texture_height,
                            tiles_for_quads)
from geotex.mapping.place import gathered_tiles
from geotex.mesh.primitives import box, torus
from geotex.mesh.record import Mesh
from geotex.mesh.topology import edge_topology
from geotex.shells import build_shell, quad_points_to_shell, save_shell
from geotex.tiles import build_tileset, save_tileset


@pytest.fixture(scope="module")
def iso_studs():
    """An isotropic two-colour set (16 tiles)."""
    return build_tileset(exemplar("studs", seed=1, resolution=6), colors=2, isotropic=True, seed=0,
                         interior="paste")


def test_flat_tile_on_flat_quad_is_the_identity_up_to_scale(studs):
    # a 6 x 6 x 1 box on a 0.25 grid: its faces are whole polycube charts; the
    # middle of the top face is farther from any edge than the offset smoothing reaches
    V, F = box((0, 0, 0), (6, 6, 1), divisions=6)
    shell = build_shell(V, F, tile_size=0.25)
    pc = shell.polycube
    colors = edge_colors(pc.layout.edge_axis, studs.n_colors, seed=0)
    tiles = tiles_for_quads(studs, pc.layout.quad_axes, pc.layout.quad_edge, colors)
    centre = pc.origin + pc.layout.quad_corners[:, 0] * 0.25
    top = np.flatnonzero((pc.layout.quad_label == 4) & (np.abs(centre[:, 0] - 2.9) < 0.2)
                         & (np.abs(centre[:, 1] - 2.9) < 0.2))
    assert top.size >= 1
    only = np.full(pc.layout.n_quads, -1)
    only[top] = tiles[top]
    uvw, quad, _, _ = gathered_tiles(studs, only)
    got = quad_points_to_shell(shell, quad, uvw, height=0.25)
    c0 = pc.origin + pc.layout.quad_corners[quad, 0] * 0.25
    # the tile moved rigidly into the +X, +Y, +Z frame of the top face and scaled
    assert np.abs(got - (c0 + uvw * 0.25)).max() < 1e-12
    # and the elements that lie wholly inside these quads come out of the full map the same
    m = mapped_tiles(shell, studs, only, scale=0.25)
    assert m.vertices.shape[0] > 0
    # every mapped face copies the tile face tile_faces names, vertex for vertex (a
    # vertex welded across a tile side keeps its twin's u, v: compare w there)
    assert m.tile_faces.shape == (len(m.faces),)
    local = studs.faces[m.tile_faces] + studs.vertex_offsets[
        np.searchsorted(studs.face_offsets, m.tile_faces, side="right") - 1][:, None]
    want, have = studs.vertices[local], m.tile_points[m.faces]
    on_side = np.isin(want[..., :2], (0.0, 1.0)).any(axis=-1)
    assert np.array_equal(want[..., 2], have[..., 2])
    assert np.array_equal(want[~on_side], have[~on_side]) and (~on_side).sum() > 100
    d = np.abs(m.vertices[:, None, :] - got[None, :, :]).max(axis=2).min(axis=1)
    assert d.max() < 1e-12


def test_welded_elements_are_closed_and_the_union_printable(torus_shell, studs):
    res = textured_solid(torus_shell, studs, seed=3)
    s = res.stats
    assert s.welded > 0 and s.open_faces_dropped == 0 and s.bare_quads == 0
    # every mapped element is closed: no boundary edge after welding
    pc = torus_shell.polycube
    colors = edge_colors(pc.layout.edge_axis, studs.n_colors, seed=3)
    m = mapped_tiles(torus_shell, studs, tiles_for_quads(studs, pc.layout.quad_axes,
                                                         pc.layout.quad_edge,
                                                         colors), scale=s.height / studs.height)
    topo = edge_topology(m.faces, m.vertices.shape[0])
    assert np.all(topo.face_count == 2)
    assert m.faces.shape[0] == s.mapped_faces
    assert res.report.printable, res.report.reasons
    assert res.report.self_intersecting_pairs == 0
    # the texture sits on the base: the solid is larger than the torus alone
    V0 = torus_shell.base_vertices
    assert np.ptp(res.vertices, axis=0).max() > np.ptp(V0, axis=0).max()


def test_stats_are_a_frozen_record_whose_dict_is_the_json_report(torus_shell, studs):
    res = textured_solid(torus_shell, studs, seed=3, check=False)
    s = res.stats
    with pytest.raises(AttributeError):
        s.faces = 0
    d = s.to_dict()
    # an unchecked run has no check-only counts; the keys keep the report's order
    assert list(d) == ["quads", "bare_quads", "height", "seed", "mapped_vertices",
                       "mapped_faces", "welded", "open_faces_dropped", "elements",
                       "union_operands", "elements_floating", "elements_folded",
                       "elements_reseated", "union_retries", "elements_lowered",
                       "elements_propped", "cavities_filled", "union_method", "union_fallbacks",
                       "vertices", "faces", "seconds"]
    assert d["faces"] == res.faces.shape[0] and d["quads"] == torus_shell.n_quads
    assert set(d["seconds"]) == {"assign", "map", "union"}
    json.dumps(d)


def test_isotropic_set_covers_a_closed_shape(torus_shell, iso_studs):
    assert iso_studs.isotropic and len(iso_studs) == 16
    res = textured_solid(torus_shell, iso_studs, seed=0)
    assert res.report.printable, res.report.reasons
    assert (res.tile_of_quad >= 0).all()


def test_same_seed_same_bytes_other_seed_other_layout(tmp_path, torus_shell, studs, iso_studs):
    a = textured_solid(torus_shell, iso_studs, seed=5, check=False)
    b = textured_solid(torus_shell, iso_studs, seed=5, check=False)
    c = textured_solid(torus_shell, iso_studs, seed=6, check=False)
    assert a.vertices.tobytes() == b.vertices.tobytes()
    assert a.faces.tobytes() == b.faces.tobytes()
    assert not np.array_equal(a.tile_of_quad, c.tile_of_quad)
    write_mesh(tmp_path / "a.stl", Mesh(a.vertices, a.faces))
    write_mesh(tmp_path / "b.stl", Mesh(b.vertices, b.faces))
    assert (tmp_path / "a.stl").read_bytes() == (tmp_path / "b.stl").read_bytes()


def test_neighbouring_quads_agree_on_their_edge_colours(torus_shell, studs):
    pc = torus_shell.polycube
    colors = edge_colors(pc.layout.edge_axis, (2, 2, 2), seed=1)
    assert set(np.unique(colors)) == {0, 1}
    side = colors[pc.layout.quad_edge]
    qa, qb = pc.layout.edge_quads[:, 0], pc.layout.edge_quads[:, 1]
    sa, sb = pc.layout.edge_sides[:, 0], pc.layout.edge_sides[:, 1]
    assert np.array_equal(side[qa, sa], side[qb, sb])


def test_planar_set_and_bad_heights_are_refused(torus_shell):
    planar = build_tileset(exemplar("studs", seed=1, resolution=6), colors=1, planar=True, interior="paste")
    with pytest.raises(InputError, match="no colours for Z"):
        textured_solid(torus_shell, planar)
    iso = build_tileset(exemplar("studs", seed=1, resolution=6), colors=1, isotropic=True, interior="paste")
    with pytest.raises(InputError, match="safe height"):
        texture_height(torus_shell, iso, 10 * torus_shell.max_height)
    with pytest.raises(InputError, match="positive"):
        texture_height(torus_shell, iso, -1.0)
    with pytest.raises(InputError, match="seed"):
        textured_solid(torus_shell, iso, seed=-1)
    h = texture_height(torus_shell, iso)
    assert h == min(iso.height * torus_shell.tile_size, torus_shell.max_height)


def test_cli_map_texture_and_errors(tmp_path, capsys, torus_shell, iso_studs):
    tiles = tmp_path / "iso.npz"
    save_tileset(tiles, iso_studs)
    shell = tmp_path / "torus.npz"
    save_shell(shell, torus_shell)
    out = tmp_path / "t.stl"
    rep = tmp_path / "t.json"
    assert main(["map", "--tiles", str(tiles), "--shell", str(shell), "-o", str(out),
                 "--report", str(rep), "--size-mm", "60", "--seed", "2"]) == 0
    text = capsys.readouterr().out
    assert "printable" in text and out.is_file()
    m = read_mesh(out)
    doc = json.loads(rep.read_text())
    # --size-mm scales the base to 60 mm before texturing: the relief adds to it
    ext = float(np.ptp(m.vertices, axis=0).max())
    assert 60.0 - 1e-3 <= ext <= 60.0 + 2 * doc["stats"]["height"] + 1e-3
    assert doc["unit"] == "mm" and doc["tile_size"] == pytest.approx(60.0 * 0.4 / 2.8)
    assert check_mesh(m.vertices, m.faces).printable
    assert doc["stats"]["seed"] == 2 and doc["check"]["printable"]
    # the one-shot from a mesh file
    src = tmp_path / "torus.obj"
    V, F = torus(1.0, 0.4, n_major=40, n_minor=20)
    write_mesh(src, Mesh(V, F))
    out2 = tmp_path / "t2.3mf"
    assert main(["texture", str(src), "--tiles", str(tiles), "--tile-size", "0.45", "-o",
                 str(out2), "--shell-out", str(tmp_path / "s2.npz")]) == 0
    assert out2.is_file() and (tmp_path / "s2.npz").is_file()
    # the files written while the check ran took their names: no hidden leftovers
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
    capsys.readouterr()
    # errors: one line, exit 2, nothing written, inputs never overwritten
    cases = [
        ["map", "--tiles", str(tiles), "--shell", str(shell), "-o", str(tiles)],
        ["map", "--tiles", "no-such-set", "--shell", str(shell), "-o", str(tmp_path / "x.stl")],
        ["map", "--tiles", str(tiles), "--shell", "no-such-shell", "-o", str(tmp_path / "x.stl")],
        ["map", "--tiles", str(tiles), "--shell", str(shell), "-o", str(tmp_path / "x.png")],
        ["map", "--tiles", str(tiles), "--shell", str(shell), "-o", str(tmp_path / "x.stl"),
         "--height", "100"],
        ["texture", str(tmp_path / "missing.obj"), "--tiles", str(tiles), "-o",
         str(tmp_path / "x.stl")],
    ]
    before = tiles.read_bytes()
    for argv in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.startswith("geotex: error:") and err.count("\n") == 1, err
        assert "PosixPath" not in err and "Errno" not in err, err
        if "--height" in argv:                  # the CLI names its flag, not the argument
            assert "--height 100 mm is above" in err and "a smaller --height" in err, err
            assert "--tile-size" not in err, err        # 'geotex map' has no such flag
    assert not (tmp_path / "x.stl").exists() and tiles.read_bytes() == before
    # an open base: the one-shot says to repair it
    open_src = tmp_path / "open.obj"
    write_mesh(open_src, Mesh(V, F[1:]))
    assert main(["texture", str(open_src), "--tiles", str(tiles), "-o",
                 str(tmp_path / "y.stl")]) == 2
    assert "geotex repair" in capsys.readouterr().err
    assert not (tmp_path / "y.stl").exists()


def _mapped_seed0(shell, tiles):
    """``tiles`` mapped over ``shell`` as the main job maps them (seed 0, default height)."""
    pc = shell.polycube
    colors = edge_colors(pc.layout.edge_axis, tiles.n_colors, seed=0)
    tq = tiles_for_quads(tiles, pc.layout.quad_axes, pc.layout.quad_edge, colors,
                         bare=pc.quad_folded)
    h = texture_height(shell, tiles)
    return mapped_tiles(shell, tiles, tq, scale=h / tiles.height, anchor=0.2 * shell.tile_size)


def _closed_sets():
    from geotex.tiles.catalog import list_tilesets

    return [r["name"] for r in list_tilesets() if r["kind"] != "planar"]


def _catalog_shells():
    from geotex.shells import list_shells

    return [r["name"] for r in list_shells()]


#: Results the folded-element test reads again (the matrix computes them first).
_KEPT_RESULTS: dict = {}


def _catalog_result(shell_name, set_name):
    """``textured_solid`` of a catalog set on a catalog shell, seed 0 (Blub + studs kept)."""
    from geotex.shells import load_named as load_shell
    from geotex.tiles.catalog import load_named as load_tiles

    key = (shell_name, set_name)
    if key in _KEPT_RESULTS:
        return _KEPT_RESULTS[key]
    res = textured_solid(load_shell(shell_name), load_tiles(set_name), seed=0)
    if key == ("blub", "studs"):
        _KEPT_RESULTS[key] = res
    return res


def _covering_pairs():
    """Every catalog set on one catalog shell and every shell under one set (Blub + studs).

    The full matrix (every set on every shell) is recorded by
    ``benchmarks/catalog_matrix.py`` (results/catalog_matrix.md); the test suite
    keeps a covering of it so CI stays short.
    """
    sets = sorted(_closed_sets(), key=lambda n: (n != "studs", n))
    shells = sorted(_catalog_shells(), key=lambda n: (n != "blub", n))
    # Blub (the slowest shell) once, then the others in turn
    cycle = shells + shells[1:] * len(sets)
    return [(cycle[i], sets[i % len(sets)]) for i in range(max(len(sets), len(shells)))]


@pytest.mark.slow
@pytest.mark.parametrize("shell_name, set_name", _covering_pairs(),
                         ids=[f"{a}-{b}" for a, b in _covering_pairs()])
def test_catalog_sets_on_catalog_shells_write_printable_files(tmp_path, shell_name, set_name):
    from geotex.printing import export_printable

    res = _catalog_result(shell_name, set_name)
    assert res.report.printable, (set_name, shell_name, res.report.reasons)
    if set_name == "weave":
        # strands run across every tile side and close into loops around the
        # object: far fewer elements than quads, few of them left out
        s = res.stats
        assert s.elements > 20 and s.elements_folded + s.elements_floating <= 0.1 * s.elements
    else:
        assert res.stats.elements > 0.5 * res.stats.quads
    # judged on the written file: float32 coordinates, corners welded on reading
    out = tmp_path / f"{set_name}.stl"
    export_printable(out, res.vertices, res.faces, report=res.report)
    mesh = read_mesh(out)
    rep = check_mesh(mesh.vertices, mesh.faces)
    assert rep.printable, (set_name, shell_name, rep.reasons)
    assert rep.components == 1                   # one body, no loose pieces
    out.unlink()


def test_catalog_has_closed_sets_and_shells():
    assert {"studs", "knurl", "chainmail", "studs-complete", "weave"} <= set(_closed_sets())
    assert {"spot", "bob", "blub", "torus"} <= set(_catalog_shells())


@pytest.mark.slow
def test_folded_elements_are_shrunk_in_place_rather_than_dropped():
    from geotex.mapping import element_contacts
    from geotex.shells import load_named as load_shell
    from geotex.tiles.catalog import load_named as load_tiles

    shell, tiles = load_shell("blub"), load_tiles("studs")
    res = _catalog_result("blub", "studs")
    s = res.stats
    assert res.report.printable, res.report.reasons
    # Blub's fins fold some studs; most of those are re-seated, smaller
    assert s.elements_reseated > s.elements_folded / 2 > 0
    # the re-seated elements are free of self-crossings (only the rest are left out)
    m = _mapped_seed0(shell, tiles)
    folded = element_contacts(m.vertices, m.faces).folded
    assert folded.size == s.elements_folded + s.elements_reseated


def test_union_composes_separate_elements_and_unites_only_those_that_meet():
    import manifold3d

    from geotex.mapping.union import element_contacts, element_pairs, united_with_base
    from geotex.mesh.primitives import icosphere
    from geotex.mesh.solid import manifold_of
    from geotex.mesh.topology import concatenated

    V, F = box((0, 0, 0), (4, 4, 1), divisions=8)
    Vs, Fs = icosphere(2)
    # spheres half sunk into the top face: most alone, a chain of three that
    # overlap one another, and a pair that overlaps
    centres = [(0.5, 0.5), (1.5, 0.5), (2.5, 0.5), (3.5, 3.5), (0.5, 2.0), (0.8, 2.0),
               (1.1, 2.0), (3.0, 2.0), (3.3, 2.1)]
    X, G = concatenated([(Vs * 0.2 + (x, y, 1.0), Fs) for x, y in centres])
    contacts = element_contacts(X, G)
    assert contacts.folded.size == 0
    assert contacts.touching.tolist() == [[4, 5], [5, 6], [7, 8]]
    label, pairs = element_pairs(X, G, touching=contacts.touching, label=contacts.label)
    assert np.array_equal(label, contacts.label) and pairs.tolist() == [[4, 5], [5, 6], [7, 8]]
    V2, F2, stats = united_with_base(V, F, X, G, contacts=contacts)
    assert (stats.elements, stats.groups, stats.floating, stats.folded) == (9, 2, 0, 0)
    # the same solid as manifold3d's union of the base and every sphere, one by one
    ref = manifold3d.Manifold.batch_boolean(
        [manifold_of(V, F)] + [manifold_of(Vs * 0.2 + (x, y, 1.0), Fs) for x, y in centres],
        manifold3d.OpType.Add)
    got = manifold_of(V2, F2)
    assert got.status() == manifold3d.Error.NoError
    assert got.volume() == pytest.approx(ref.volume(), rel=1e-9)
    assert got.genus() == 0 and len(F2) == ref.num_tri()
    rep = check_mesh(V2, F2)
    assert rep.printable, rep
    # left out: an element of the chain (the other two still meet) and a lone one
    exclude = np.zeros(9, dtype=bool)
    exclude[[0, 4]] = True
    V3, F3, stats = united_with_base(V, F, X, G, contacts=contacts, exclude=exclude)
    assert stats.elements == 7
    ref = manifold3d.Manifold.batch_boolean(
        [manifold_of(V, F)] + [manifold_of(Vs * 0.2 + (x, y, 1.0), Fs)
                               for k, (x, y) in enumerate(centres) if not exclude[k]],
        manifold3d.OpType.Add)
    assert manifold_of(V3, F3).volume() == pytest.approx(ref.volume(), rel=1e-9)
    # same inputs, same bytes
    V4, F4, _ = united_with_base(V, F, X, G, contacts=contacts)
    assert V4.tobytes() == V2.tobytes() and F4.tobytes() == F2.tobytes()


def test_element_contacts_equal_the_full_exact_test_on_a_real_layout(monkeypatch):
    """The sweep by elements gives the folded set and touching pairs of the
    plain exact test of all mapped faces (catalog shell Spot, studs)."""
    import geotex.check.intersections as gi
    from geotex.check.intersections import self_intersecting_pairs
    from geotex.mapping import element_contacts
    from geotex.mesh.topology import face_components
    from geotex.shells import load_named as load_shell
    from geotex.tiles.catalog import load_named as load_tiles

    shell, tiles = load_shell("spot"), load_tiles("studs")
    m = _mapped_seed0(shell, tiles)
    X, G = m.vertices, m.faces
    # the old element_contacts: one exact test of all faces on the global grid
    _, label = face_components(G, X.shape[0])
    pairs = self_intersecting_pairs(X, G)
    a, b = label[pairs[:, 0]], label[pairs[:, 1]]
    same = a == b
    touching = np.unique(np.sort(np.stack([a[~same], b[~same]], axis=1), axis=1), axis=0)
    monkeypatch.setattr(gi, "JIT_MIN_SIZE", 0)          # the sweep at any size
    swept = []
    real = gi._part_loops
    monkeypatch.setattr(gi, "_part_loops", lambda *args: swept.append(1) or real(*args))
    c = element_contacts(X, G)
    assert swept
    assert np.array_equal(c.label, label)
    assert np.array_equal(c.folded, np.unique(a[same]))
    assert np.array_equal(c.touching, touching.reshape(-1, 2))
    assert c.touching.size                    # studs meet there (none is folded)
    # the map's own element numbering is face_components' (textured_solid hands it over)
    assert np.array_equal(m.element[G[:, 0]], label)
    c2 = element_contacts(X, G, label=m.element[G[:, 0]])
    assert all(np.array_equal(x, y) for x, y in zip(c, c2))


def test_element_contacts_rejects_labels_that_are_not_one_per_face():
    from geotex.errors import InputError
    from geotex.mapping.union import element_contacts
    from geotex.mesh.primitives import icosphere

    X, G = icosphere(1)
    with pytest.raises(InputError, match="one integer per face"):
        element_contacts(X, G, label=np.zeros(len(G) - 1, dtype=np.int64))
    with pytest.raises(InputError, match="one integer per face"):
        element_contacts(X, G, label=np.zeros(len(G)))
    assert element_contacts(X, G, label=np.zeros(len(G), dtype=np.int32)).folded.size == 0

