"""Shells: construction, point location on quads, files, catalog and CLI."""

from __future__ import annotations

import numpy as np
import pytest

from geotex.check.intersections import self_intersecting_pairs
from geotex.cli import main
from geotex.errors import InputError, MeshFileError, MissingFileError
from geotex.mesh.primitives import box, torus
from geotex.shells import (build_shell, list_shells, load_shell, locate_on_quads,
                           quad_points_to_base, quad_points_to_shell, save_shell, shell_path)


@pytest.fixture(scope="module")
def torus_shell():
    V, F = torus(n_major=48, n_minor=24)
    return build_shell(V, F, tile_size=0.25, name="torus")


def _edge_uv(side, t):
    """(E, T, 2) points at parameter t along local edge ``side`` (in its running order)."""
    z, o = np.zeros_like(t), np.ones_like(t)
    choices = np.stack([np.stack([t, z], -1), np.stack([o, t], -1),
                        np.stack([1 - t, o], -1), np.stack([z, 1 - t], -1)])  # (4, T, 2)
    return choices[side]


def test_box_shell_corners_exact():
    V, F = box((0, 0, 0), (1, 1, 1), divisions=2)
    s = build_shell(V, F, tile_size=0.25)
    q = np.repeat(np.arange(s.n_quads), 4)
    uv = np.tile([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]], (s.n_quads, 1))
    x, d = quad_points_to_base(s, q, uv)
    corners = s.polycube.origin + s.polycube.layout.quad_corners.reshape(-1, 3) * 0.25
    assert np.allclose(x, corners, atol=1e-12)
    assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
    assert np.array_equal(s.base_vertices, V) and np.array_equal(s.base_faces, F)


def test_locate_matches_polycube_point(torus_shell):
    s = torus_shell
    pc = s.polycube
    rng = np.random.default_rng(0)
    k = 5000
    q = rng.integers(0, s.n_quads, k)
    uv = rng.random((k, 2))
    uv[:50] = 0.0  # quad corners
    f, b = locate_on_quads(s, q, uv)
    assert np.all(b >= 0) and np.allclose(b.sum(axis=1), 1.0)
    assert np.all(pc.layout.face_quad[f] == q)
    p = np.einsum("ki,kij->kj", b, pc.P[pc.F[f]])
    c = pc.layout.quad_corners[q].astype(float)
    expected = c[:, 0] + uv[:, :1] * (c[:, 1] - c[:, 0]) + uv[:, 1:] * (c[:, 3] - c[:, 0])
    assert np.abs(p - expected).max() < 1e-12


def test_shared_edges_agree(torus_shell):
    s = torus_shell
    pc = s.polycube
    t = np.linspace(0.0, 1.0, 7)
    E = pc.layout.edge_axis.size
    qa, qb = pc.layout.edge_quads[:, 0], pc.layout.edge_quads[:, 1]
    sa, sb = pc.layout.edge_sides[:, 0], pc.layout.edge_sides[:, 1]
    uva = _edge_uv(sa, t).reshape(-1, 2)
    uvb = _edge_uv(sb, 1.0 - t).reshape(-1, 2)  # the neighbour runs the other way
    xa, _ = quad_points_to_base(s, np.repeat(qa, t.size), uva)
    xb, _ = quad_points_to_base(s, np.repeat(qb, t.size), uvb)
    assert np.abs(xa - xb).max() < 1e-12
    assert E == pc.layout.quad_edge.max() + 1


def test_max_height_is_safe(torus_shell):
    s = torus_shell
    assert 0 < s.max_height
    Y, F = s.polycube.Y, s.polycube.F
    Vo = Y + s.max_height * s.D
    n = Y.shape[0]
    Vc = np.vstack([Y, Vo])
    Fc = np.vstack([F, F[:, ::-1] + n])
    assert self_intersecting_pairs(Vc, Fc).shape[0] == 0
    pts = quad_points_to_shell(s, np.array([0, 1]), [[0.5, 0.5, 1.0], [0.2, 0.3, 0.0]],
                               height=s.max_height)
    assert pts.shape == (2, 3)
    with pytest.raises(InputError, match="max_height"):
        quad_points_to_shell(s, np.array([0]), [[0.5, 0.5, 1.0]], height=2 * s.max_height)
    with pytest.raises(InputError, match="quad_ids"):
        locate_on_quads(s, np.array([s.n_quads]), [[0.5, 0.5]])


def test_file_round_trip_and_reproducible(tmp_path, torus_shell):
    a = tmp_path / "a.npz"
    save_shell(a, torus_shell)
    s2 = load_shell(a)
    for k in ("Y", "F", "P", "quad_folded", "origin"):
        assert np.array_equal(getattr(s2.polycube, k), getattr(torus_shell.polycube, k))
    for k in ("quad_grid", "quad_label", "quad_corners", "quad_edge", "quad_edge_forward",
              "edge_axis", "edge_quads", "edge_sides"):
        assert np.array_equal(getattr(s2.polycube.layout, k),
                              getattr(torus_shell.polycube.layout, k))
    assert np.array_equal(s2.base_vertices, torus_shell.base_vertices)
    assert s2.polycube.diagnostics.distortion == torus_shell.polycube.diagnostics.distortion
    assert np.array_equal(s2.D, torus_shell.D) and s2.max_height == torus_shell.max_height
    # same input -> byte-identical file
    V, F = torus(n_major=48, n_minor=24)
    b = tmp_path / "b.npz"
    save_shell(b, build_shell(V, F, tile_size=0.25, name="torus"))
    assert a.read_bytes() == b.read_bytes()
    # locate gives identical answers after loading
    q = np.arange(s2.n_quads)
    uv = np.full((q.size, 2), 0.3)
    assert np.array_equal(locate_on_quads(s2, q, uv)[0], locate_on_quads(torus_shell, q, uv)[0])


def test_corrupted_and_wrong_files(tmp_path, torus_shell):
    good = tmp_path / "s.npz"
    save_shell(good, torus_shell)
    bad = tmp_path / "bad.npz"
    bad.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    with pytest.raises(MeshFileError, match="truncated or corrupted"):
        load_shell(bad)
    other = tmp_path / "other.npz"
    np.savez(other, x=np.zeros(3))
    with pytest.raises(MeshFileError, match="not a geotex shell"):
        load_shell(other)
    # a shell whose quads no longer form a closed surface
    import io
    import zipfile
    buf = io.BytesIO()
    with zipfile.ZipFile(good) as zin, zipfile.ZipFile(buf, "w") as zout:
        for item in zin.infolist():
            data = zin.read(item.filename)
            if item.filename == "quad_label.npy":
                arr = np.load(io.BytesIO(data))
                arr = arr[:-3]
                out = io.BytesIO()
                np.save(out, arr)
                data = out.getvalue()
            zout.writestr(item, data)
    broken = tmp_path / "broken.npz"
    broken.write_bytes(buf.getvalue())
    with pytest.raises(MeshFileError, match="inconsistent shell file"):
        load_shell(broken)
    with pytest.raises(MissingFileError):
        load_shell(tmp_path / "missing.npz")
    with pytest.raises(InputError, match=".npz"):
        save_shell(tmp_path / "x.obj", torus_shell)


def test_catalog_is_shipped():
    rows = list_shells()
    names = {r["name"] for r in rows}
    assert {"spot", "torus"} <= names
    for r in rows:
        assert r["bytes"] <= 2_000_000
        assert shell_path(r["name"]).is_file()
    s = load_shell(shell_path("torus"))
    assert s.n_quads == next(r["quads"] for r in rows if r["name"] == "torus")
    with pytest.raises(MissingFileError, match="catalog"):
        shell_path("no-such-shell")


def test_cli_build_list_and_errors(tmp_path, capsys):
    from geotex.io import write_mesh
    from geotex.mesh.record import Mesh

    V, F = box((0, 0, 0), (1, 1, 1), divisions=2)
    src = tmp_path / "cube.obj"
    write_mesh(src, Mesh(V, F))
    out = tmp_path / "cube.npz"
    assert main(["shell", "build", str(src), "-o", str(out), "--tile-size", "0.25"]) == 0
    text = capsys.readouterr().out
    assert "96 quads" in text and "max height" in text and out.is_file()
    assert "distortion" in text
    assert load_shell(out).n_quads == 96
    assert main(["shell", "list"]) == 0
    assert "torus" in capsys.readouterr().out
    # open mesh: one-line error, exit 2, no output file
    open_src = tmp_path / "open.obj"
    write_mesh(open_src, Mesh(V, F[1:]))
    out2 = tmp_path / "open.npz"
    assert main(["shell", "build", str(open_src), "-o", str(out2)]) == 2
    err = capsys.readouterr().err
    assert "geotex repair" in err and err.count("\n") == 1 and not out2.exists()
    assert main(["shell", "build", str(src), "-o", str(src)]) == 2


def test_side_coordinate_runs_the_same_way_in_both_quads(torus_shell):
    """A point at coordinate t along a shared edge is the same seen from both quads."""
    s = torus_shell
    pc = s.polycube
    t = np.linspace(0.0, 1.0, 5)

    def side_uv(side):
        z, o = np.zeros_like(t), np.ones_like(t)
        table = np.stack([np.stack([t, z], -1), np.stack([o, t], -1), np.stack([t, o], -1),
                          np.stack([z, t], -1)])
        return table[side].reshape(-1, 2)

    qa, qb = pc.layout.edge_quads[:, 0], pc.layout.edge_quads[:, 1]
    uva, uvb = side_uv(pc.layout.edge_sides[:, 0]), side_uv(pc.layout.edge_sides[:, 1])
    ca = pc.layout.quad_corners[np.repeat(qa, t.size)].astype(float)
    cb = pc.layout.quad_corners[np.repeat(qb, t.size)].astype(float)
    pa = ca[:, 0] + uva[:, :1] * (ca[:, 1] - ca[:, 0]) + uva[:, 1:] * (ca[:, 3] - ca[:, 0])
    pb = cb[:, 0] + uvb[:, :1] * (cb[:, 1] - cb[:, 0]) + uvb[:, 1:] * (cb[:, 3] - cb[:, 0])
    assert np.array_equal(pa, pb)
    xa, _ = quad_points_to_base(s, np.repeat(qa, t.size), uva)
    xb, _ = quad_points_to_base(s, np.repeat(qb, t.size), uvb)
    assert np.abs(xa - xb).max() < 1e-12


def test_cli_automatic_tile_size_and_too_large_error(tmp_path, capsys):
    from scipy.spatial.transform import Rotation

    from geotex.io import write_mesh
    from geotex.mesh.primitives import plate_with_holes
    from geotex.mesh.record import Mesh

    V, F = box((0, 0, 0), (1, 0.25, 0.25), divisions=2)      # a bar: few quads
    src = tmp_path / "bar.obj"
    write_mesh(src, Mesh(V, F))
    out = tmp_path / "bar.npz"
    assert main(["shell", "build", str(src), "-o", str(out)]) == 0
    assert "162 quads of 0.08333 (chosen after 1 attempts)" in capsys.readouterr().out
    shell = load_shell(out)
    assert shell.tile_size == pytest.approx(1 / 12)
    assert shell.recipe["tile_size"] == shell.tile_size and shell.recipe["tile_size_automatic"]
    assert shell.polycube.diagnostics.tile_search["attempts"][0]["result"] == "ok"
    # an explicit size too large for the holes: one line naming a size that works
    V, F = plate_with_holes(3, hole=0.2, bar=0.6, thickness=0.4, cell=0.06)
    V = V @ Rotation.from_euler("zx", [30, 20], degrees=True).as_matrix().T
    plate = tmp_path / "plate.obj"
    write_mesh(plate, Mesh(V, F))
    ts = float(np.ptp(V, axis=0).max()) / 12
    out2 = tmp_path / "plate.npz"
    assert main(["shell", "build", str(plate), "-o", str(out2), "--tile-size", f"{ts:.6f}"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and not out2.exists()
    assert "--tile-size" in err and "genus 3" in err and "resolves it" in err


def test_offset_surface_pairs_searched_again_only_where_directions_moved(torus_shell, monkeypatch):
    """The incremental search of the pinch test gives the full search's answer,
    normalised by one box (the surface's grown by the height) whatever the
    directions, so that turned directions at the box's extremes keep it."""
    import geotex.check.intersections as gi

    s = torus_shell
    Y, F = s.polycube.Y, s.polycube.F
    n = Y.shape[0]
    h = 3.0 * s.max_height                        # tall enough to cross somewhere
    box = np.stack([Y[F].reshape(-1, 3).min(axis=0) - h, Y[F].reshape(-1, 3).max(axis=0) + h])

    def full(D, h, box=box):
        return self_intersecting_pairs(np.vstack([Y, Y + h * D]),
                                       np.vstack([F, F[:, ::-1] + n]), box=box)

    calls = []
    touching = gi.self_intersecting_pairs_touching
    monkeypatch.setattr(gi, "self_intersecting_pairs_touching",
                        lambda *a, **k: calls.append(a[2].size) or touching(*a, **k))
    first = gi.offset_surface_pairs(Y, F, s.D, h)
    assert first[1].shape[0] > 0 and np.array_equal(first[2], box)
    np.testing.assert_array_equal(first[1], full(s.D, h))
    # some directions turned, one of them at the surface's largest x (a box
    # of the stacked mesh alone could move): the kept pairs plus a local search
    D = s.D.copy()
    rows = np.random.default_rng(3).choice(n, 40, replace=False)
    rows[0] = int(np.argmax(Y[:, 0]))
    D[rows] = np.roll(D[rows], 1, axis=1)
    D[rows[0]] = [1.0, 0.0, 0.0]
    again = gi.offset_surface_pairs(Y, F, D, h, previous=first)
    assert len(calls) == 1 and 0 < calls[0] < F.shape[0]
    expected = full(D, h)
    assert not np.array_equal(expected, first[1])          # the turn changed the answer
    np.testing.assert_array_equal(again[1], expected)
    # nothing moved: the previous answer as it is
    same = gi.offset_surface_pairs(Y, F, D, h, previous=again)
    assert len(calls) == 1
    np.testing.assert_array_equal(same[1], expected)
    # a longer direction takes the offset out of the box: the full search, by the
    # larger box
    far = D.copy()
    far[rows[0]] = [2.0, 0.0, 0.0]
    grown = gi.offset_surface_pairs(Y, F, far, h, previous=again)
    assert len(calls) == 1 and grown[2][1, 0] > box[1, 0]
    np.testing.assert_array_equal(grown[1], full(far, h, grown[2]))


def test_bare_warning_on_the_catalog_blub_names_the_flag():
    """The catalog Blub (tile 0.095) leaves the tips of its fins out of the
    texture's reach; its file predates the record, so the share is computed
    from the shell. The catalog Spot, rebuilt with the reach step, records
    none out of reach (its horns) and does not warn."""
    from geotex.param.polycube_size import MAX_BARE
    from geotex.shells import bare_area, bare_warning, load_named

    blub = load_named("blub")
    assert "bare" not in blub.polycube.diagnostics.coverage
    assert bare_area(blub) > MAX_BARE
    line = bare_warning(blub, "use a smaller --tile-size")
    assert line.startswith("warning: ") and line.endswith("--tile-size") and "\n" not in line
    spot = load_named("spot")
    assert spot.polycube.diagnostics.coverage["bare"] == 0.0
    assert bare_warning(spot, "use a smaller --tile-size") is None
    assert bare_warning(load_named("torus"), "use a smaller --tile-size") is None


def _crossing_above(L):
    """A square at z = 0 and a small tilted triangle above it spanning z = L +- 0.005,
    both offset straight up, and a triangle whose offset flips from height 0.9."""
    a = 0.9 / np.sqrt(2)
    V = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0],
                  [0.4, 0.4, L - 0.005], [0.6, 0.4, L - 0.005], [0.5, 0.6, L + 0.005],
                  [5 - a, 0, 0], [5 + a, 0, 0], [5, 1, 0]], dtype=np.float64)
    F = np.array([[0, 1, 2], [0, 2, 3], [4, 5, 6], [7, 8, 9]], dtype=np.int64)
    D = np.tile([0.0, 0.0, 1.0], (10, 1))
    D[7], D[8] = [np.sqrt(0.5), 0, np.sqrt(0.5)], [-np.sqrt(0.5), 0, np.sqrt(0.5)]
    return V, F, D


def test_safe_height_is_the_whole_surface_bisection_when_the_shrinking_one_misses(monkeypatch):
    """The shrinking bisection follows the flipping triangle alone and ends at a
    height where the square's offset crosses the small triangle: the bisection
    is redone on the whole surface, to the same height as a whole-surface
    bisection from the start, without testing that height twice."""
    import geotex.shells.build as build
    from geotex.mesh.geometry import face_cross

    tested = []
    defects = build._offset_defects

    def recorded(V, F, D, h, normals, *, first=False):
        tested.append((F.shape[0], h))
        return defects(V, F, D, h, normals, first=first)

    monkeypatch.setattr(build, "_offset_defects", recorded)
    V, F, D = _crossing_above(0.5)                # no crossing near the end
    lo = build.max_offset_height(V, F, D, steps=6, upper=1.0)
    assert lo == 0.890625 and [t[0] for t in tested] == [4, 1, 1, 1, 1, 1, 1, 4]
    V, F, D = _crossing_above(lo)                 # now the square's offset crosses there
    tested.clear()
    got = build.max_offset_height(V, F, D, steps=6, upper=1.0)
    whole = [h for m, h in tested if m == 4]
    assert len(whole) == len(set(whole)) == 7 and lo in whole
    tested.clear()
    assert got == build._bisected_height(V, F, D, face_cross(V, F), 1.0, 6) == 0.875
