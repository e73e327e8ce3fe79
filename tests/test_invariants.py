"""Corpus-wide invariants (libigl style): every valid closed mesh x every invariant.

The corpus: the closed samples bundled with geotex (Spot, Blub, Bob: see
``geotex/data/NOTICE.md``), the valid closed meshes of ``tests/data`` (see its
``NOTICE.md``), and generated shapes of known genus.  Each invariant holds for
any closed, manifold, outward-oriented, self-intersection-free triangle mesh.
"""

from __future__ import annotations

from functools import lru_cache
from pathlib import Path

import numpy as np
import pytest

from geotex.check import check_mesh
from geotex.check.intersections import self_intersecting_pairs
from geotex.data import sample_path
from geotex.io import WRITE_FORMATS, read_mesh, write_mesh
from geotex.mesh import Mesh
from geotex.mesh.geometry import face_areas, face_normals, mean_edge_length, signed_volume
from geotex.mesh.primitives import box, icosphere, plate_with_holes, torus
from geotex.mesh.topology import compacted, edge_topology

DATA = Path(__file__).parent / "data" / "broken"

#: name -> (loader, genus)
CORPUS = {
    "spot": (lambda: _read(sample_path("spot")), 0),
    "blub": (lambda: _read(sample_path("blub")), 0),
    "bob": (lambda: _read(sample_path("bob")), 1),
    "plate_holes_trimesh": (lambda: _read(DATA / "plate_holes_trimesh.STL"), 5),
    "stl_box_binary_gc": (lambda: _read(DATA / "stl_box_binary_gc.stl"), 0),
    "icosphere": (lambda: icosphere(3), 0),
    "torus": (lambda: torus(n_major=32, n_minor=16), 1),
    "box": (lambda: box((-1.0, -2.0, 0.5), (2.0, 1.0, 1.5), divisions=3), 0),
    "plate_with_holes_2": (lambda: plate_with_holes(2, cell=0.15), 2),
}
NAMES = sorted(CORPUS)

#: formats that store float32 coordinates (binary STL, glTF); the others are exact
FLOAT32_FORMATS = {".stl", ".glb"}


def _read(path):
    m = read_mesh(path)
    return m.vertices, m.faces


@lru_cache(maxsize=None)
def _mesh(name):
    V, F = CORPUS[name][0]()
    V.setflags(write=False)
    F.setflags(write=False)
    return V, F


@lru_cache(maxsize=None)
def _report(name):
    return check_mesh(*_mesh(name))


@pytest.mark.parametrize("name", NAMES)
def test_printable_with_positive_volume(name):
    rep = _report(name)
    assert rep.printable, rep.reasons
    assert rep.volume > 0 and rep.outward


@pytest.mark.parametrize("name", NAMES)
def test_unique_edges_are_three_halves_of_the_faces(name):
    V, F = _mesh(name)
    topo = edge_topology(F, V.shape[0])
    assert 2 * topo.edges.shape[0] == 3 * F.shape[0]
    assert topo.boundary.size == 0 and topo.non_manifold.size == 0


@pytest.mark.parametrize("name", NAMES)
def test_euler_characteristic_matches_the_genus(name):
    V, F = _mesh(name)
    genus = CORPUS[name][1]
    E = edge_topology(F, V.shape[0]).edges.shape[0]
    assert V.shape[0] - E + F.shape[0] == 2 - 2 * genus
    rep = _report(name)
    assert rep.euler_characteristic == 2 - 2 * genus and rep.genus == genus


@pytest.mark.parametrize("name", NAMES)
def test_faces_point_outward(name):
    V, F = _mesh(name)
    assert signed_volume(V, F) > 0
    # the divergence theorem: sum of area-weighted normals vanishes on a closed surface
    N = face_normals(V, F) * face_areas(V, F)[:, None]
    scale = face_areas(V, F).sum()
    assert np.abs(N.sum(axis=0)).max() <= 1e-9 * scale


@pytest.mark.parametrize("name", NAMES)
def test_no_self_intersections(name):
    V, F = _mesh(name)
    assert self_intersecting_pairs(V, F).shape == (0, 2)


@pytest.mark.parametrize("name", NAMES)
def test_mean_edge_length_is_positive(name):
    V, F = _mesh(name)
    h = mean_edge_length(V, F)
    assert np.isfinite(h) and h > 0
    # every edge of a closed manifold has two faces: counting per face weighs all twice
    assert mean_edge_length(V, F, per_face=True) == pytest.approx(h, rel=1e-12)


@pytest.mark.parametrize("name", NAMES)
def test_compacted_is_idempotent(name):
    V, F = _mesh(name)
    V1, F1 = compacted(V, F)
    V2, F2 = compacted(V1, F1)
    assert np.array_equal(V1, V2) and np.array_equal(F1, F2)
    # a closed mesh references every vertex: nothing to drop
    assert np.array_equal(V1, V) and np.array_equal(F1, F)


@pytest.mark.parametrize("fmt", WRITE_FORMATS)
@pytest.mark.parametrize("name", NAMES)
def test_write_read_round_trip_keeps_the_geometry(tmp_path, name, fmt):
    V, F = _mesh(name)
    path = write_mesh(tmp_path / f"m{fmt}", Mesh(V, F))
    back = read_mesh(path)
    want = V.astype(np.float32).astype(np.float64) if fmt in FLOAT32_FORMATS else V
    # same faces in the same order, each corner at the stored position
    assert back.faces.shape == F.shape
    assert np.array_equal(back.vertices[back.faces], want[F])
    # writing it again gives the same bytes (same name: OBJ records it)
    (tmp_path / "again").mkdir()
    again = write_mesh(tmp_path / "again" / f"m{fmt}", Mesh(V, F))
    assert again.read_bytes() == path.read_bytes()


@pytest.mark.parametrize("name", NAMES)
def test_repeats_are_deterministic(name):
    V, F = _mesh(name)
    a, b = check_mesh(V, F).to_dict(), _report(name).to_dict()
    assert a == b
    assert np.array_equal(self_intersecting_pairs(V, F), self_intersecting_pairs(V, F))
    assert mean_edge_length(V, F) == mean_edge_length(V.copy(), F.copy())
