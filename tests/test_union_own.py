"""The own local union wired into united_with_base and the main job, and its fallbacks."""

from __future__ import annotations

import manifold3d
import numpy as np
import pytest

import geotex.mapping.union as union_module
from geotex.check import check_mesh
from geotex.errors import InputError
from geotex.mapping import textured_solid
from geotex.mapping.crossing import CrossingUnion
from geotex.mapping.union import (OWN_ELEMENTS_PER_BASE_FACE, OWN_SHARE, element_contacts,
                                  united_with_base)
from geotex.mesh.primitives import box, icosphere
from geotex.mesh.solid import manifold_of
from geotex.mesh.topology import concatenated


def _spheres(centres, z):
    Vs, Fs = icosphere(2)
    parts = [(Vs * 0.2 + (x, y, z), Fs) for x, y in centres]
    return parts, concatenated(parts)


def _reference(V, F, parts):
    return manifold3d.Manifold.batch_boolean(
        [manifold_of(V, F)] + [manifold_of(X, G) for X, G in parts], manifold3d.OpType.Add)


# spheres sunk into the top face of a box: four alone, a chain of three and a pair
CENTRES = [(0.5, 0.5), (1.5, 0.5), (2.5, 0.5), (3.5, 3.5), (0.5, 2.0), (0.8, 2.0),
           (1.1, 2.0), (3.0, 2.0), (3.3, 2.1)]


def test_own_union_is_the_boolean_solid_and_deterministic():
    V, F = box((0, 0, 0), (4, 4, 1), divisions=8)
    # centres off the top plane: every crossing sign is proved
    parts, (X, G) = _spheres(CENTRES, 1.0123)
    contacts = element_contacts(X, G)
    assert contacts.touching.tolist() == [[4, 5], [5, 6], [7, 8]]
    V2, F2, stats = united_with_base(V, F, X, G, contacts=contacts, union="own")
    assert (stats.method, stats.fallbacks) == ("own", 0)
    assert (stats.elements, stats.groups, stats.floating, stats.folded) == (9, 2, 0, 0)
    ref = _reference(V, F, parts)
    got = manifold_of(V2, F2)
    assert got.status() == manifold3d.Error.NoError
    assert got.volume() == pytest.approx(ref.volume(), rel=1e-9)
    assert got.genus() == ref.genus() == 0
    assert check_mesh(V2, F2).printable
    Vb, Fb, sb = united_with_base(V, F, X, G, contacts=contacts, union="boolean")
    assert (sb.method, sb.fallbacks) == ("boolean", 0)
    assert manifold_of(Vb, Fb).volume() == pytest.approx(got.volume(), rel=1e-9)
    # the default is the boolean
    Vd, Fd, sd = united_with_base(V, F, X, G, contacts=contacts)
    assert sd.method == "boolean" and Fd.tobytes() == Fb.tobytes()
    # same inputs, same bytes
    V3, F3, _ = united_with_base(V, F, X, G, contacts=contacts, union="own")
    assert V3.tobytes() == V2.tobytes() and F3.tobytes() == F2.tobytes()


def test_an_element_the_own_union_cannot_decide_sends_the_whole_union_to_the_boolean():
    V, F = box((0, 0, 0), (4, 4, 1), divisions=8)
    # sphere centres on the top plane: their equator vertices lie on it (no sign)
    parts, (X, G) = _spheres(CENTRES[:4], 1.0)
    assert np.any(X[:, 2] == 1.0)
    V2, F2, stats = united_with_base(V, F, X, G, union="own")
    assert (stats.method, stats.fallbacks, stats.elements) == ("boolean", 1, 4)
    Vb, Fb, _ = united_with_base(V, F, X, G, union="boolean")
    assert V2.tobytes() == Vb.tobytes() and F2.tobytes() == Fb.tobytes()


def test_auto_sends_the_union_where_the_lone_elements_are_most_of_the_faces():
    V, F = box((0, 0, 0), (4, 4, 1), divisions=2)
    # only lone elements, more faces than the base: the own union
    lone = [(0.5 + 0.6 * i, 0.5 + 0.6 * j) for i in range(5) for j in range(5)]
    parts, (X, G) = _spheres(lone, 1.0123)
    assert len(G) >= OWN_SHARE * len(F) and len(lone) <= OWN_ELEMENTS_PER_BASE_FACE * len(F)
    _, _, stats = united_with_base(V, F, X, G, union="auto")
    assert stats.method == "own"
    # a coarse base (12 faces) under 49 lone elements (4.1 per face): still the own
    # union, and its float32 result passes the check; under 81 (6.75 per face): the boolean
    Vc, Fc = box((0, 0, 0), (4, 4, 1))
    for n, step, method in ((7, 0.5, "own"), (9, 0.42, "boolean")):
        many = [(0.3 + step * i, 0.3 + step * j) for i in range(n) for j in range(n)]
        _, (Xm, Gm) = _spheres(many, 1.0123)
        assert (len(many) > OWN_ELEMENTS_PER_BASE_FACE * len(Fc)) == (method == "boolean")
        V2, F2, stats = united_with_base(Vc, Fc, Xm, Gm, union="auto")
        assert stats.method == method and stats.fallbacks == 0
        assert check_mesh(V2.astype(np.float32).astype(np.float64), F2).printable
    # a long chain of meeting elements and two lone ones: the boolean
    chain = [(0.5 + 0.15 * i, 2.0) for i in range(20)] + [(0.5, 3.5), (3.5, 3.5)]
    parts, (X, G) = _spheres(chain, 1.0123)
    _, _, stats = united_with_base(V, F, X, G, union="auto")
    assert stats.method == "boolean" and stats.fallbacks == 0


def test_bad_union_is_refused():
    V, F = box((0, 0, 0), (4, 4, 1))
    _, (X, G) = _spheres(CENTRES[:1], 1.0123)
    with pytest.raises(InputError, match="union"):
        united_with_base(V, F, X, G, union="fast")


def test_main_job_reports_its_union_and_the_check_guards_the_own_one(torus_shell, studs,
                                                                     monkeypatch):
    own = textured_solid(torus_shell, studs, seed=3, union="own")
    boolean = textured_solid(torus_shell, studs, seed=3, union="boolean")
    assert own.report.printable and boolean.report.printable
    assert (own.stats.union_method, own.stats.union_fallbacks) == ("own", 0)
    assert (boolean.stats.union_method, boolean.stats.union_fallbacks) == ("boolean", 0)
    assert own.stats.to_dict()["union_method"] == "own"
    # unchecked, "auto" is the boolean (the check is the own union's guard)
    unchecked = textured_solid(torus_shell, studs, seed=3, check=False, union="auto")
    assert unchecked.stats.union_method == "boolean"
    # so is the job's default ("auto") unchecked
    assert textured_solid(torus_shell, studs, seed=3, check=False).stats.union_method == "boolean"
    with pytest.raises(InputError, match="union"):
        textured_solid(torus_shell, studs, seed=3, union="fast")

    # an own union that returns a broken solid (one face missing: open) is
    # caught by the job's check and redone by the boolean of the same operands
    real = union_module.crossing_union

    def broken(*args, **kwargs):
        r = real(*args, **kwargs)
        return CrossingUnion(r.vertices, r.faces[1:], r.left_out)

    monkeypatch.setattr(union_module, "crossing_union", broken)
    res = textured_solid(torus_shell, studs, seed=3, union="own")
    assert (res.stats.union_method, res.stats.union_fallbacks) == ("boolean", 1)
    assert res.stats.union_retries == boolean.stats.union_retries
    assert res.report.printable
    assert res.vertices.tobytes() == boolean.vertices.tobytes()
    assert res.faces.tobytes() == boolean.faces.tobytes()
