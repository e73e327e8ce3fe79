"""Planar height-and-tilt texture onto other bases through field-aligned charts."""

from __future__ import annotations

import igl
import numpy as np
import pytest

from geotex.check.intersections import self_intersecting_pairs
from geotex.errors import InputError
from geotex.heighttilt import (apply_texture, base_normals, bumpy_plane, decode_tilt,
                               extract_texture, refine_base, transfer_planar)
from geotex.heighttilt.transfer import _project
from geotex.mesh.primitives import grid_plane, icosphere
from geotex.mesh.topology import edge_topology

SCALE = 0.8


@pytest.fixture(scope="module")
def plane():
    V0, F, Vs = bumpy_plane(16, 16, seed=0, periodic=True, radius=0.15, bumps=6, height=0.1,
                            lean_degrees=40, direction=(1, 0))
    tex, _ = extract_texture(V0, F, base=Vs)
    return V0, F, Vs, tex


@pytest.fixture(scope="module")
def on_sphere(plane):
    V0, F, Vs, tex = plane
    Vd, Fd = icosphere(2)
    res = transfer_planar(Vs, F, tex, Vd, Fd, scale=SCALE)
    return res, apply_texture(res.vertices, res.faces, res.texture)


def test_periodic_bumpy_plane_tiles_seamlessly():
    V0, F, Vs = bumpy_plane(12, 12, seed=3, periodic=True, radius=0.2)
    d = V0 - Vs
    for axis in (0, 1):
        a = np.flatnonzero(np.isclose(Vs[:, axis], 0.0))
        b = np.flatnonzero(np.isclose(Vs[:, axis], 1.0))
        a, b = a[np.argsort(Vs[a, 1 - axis])], b[np.argsort(Vs[b, 1 - axis])]
        np.testing.assert_allclose(d[a], d[b], atol=1e-15)
    assert np.abs(d).max() > 0.05                  # the bumps do cross the borders somewhere


def test_identity_on_a_finer_flat_grid_reproduces_the_texture(plane):
    V0, F, Vs, tex = plane
    Vt, Ft = grid_plane(32, 32)
    field = np.tile([1.0, 0.0, 0.0], (len(Ft), 1))
    res = transfer_planar(Vs, F, tex, Vt, Ft, scale=1.0, field=field, refine="none",
                          patch_radius=0.4, start_face=0, start_uv=Vt[Ft[0]].mean(axis=0)[:2])
    assert res.n_patches > 5                       # several charts, matched across seams
    assert np.array_equal(res.faces, Ft)
    f, B = _project(np.column_stack([Vt[:, :2], np.zeros(len(Vt))]), Vs, F)
    h_ref = np.einsum("pk,pk->p", B, tex.height[F[f]])
    np.testing.assert_allclose(res.texture.height, h_ref, atol=1e-12)     # measured 3.6e-15
    t_ref = np.einsum("pk,pkd->pd", B, decode_tilt(Vs, F, tex.tilt, tex.residual)[F[f]])
    t_out = decode_tilt(Vt, Ft, res.texture.tilt, res.texture.residual)
    np.testing.assert_allclose(t_out, t_ref, atol=1e-9)                    # measured 5e-13
    # the 1-form alone (line integrals of the source tilt) is close too
    t_form = decode_tilt(Vt, Ft, res.texture.tilt)
    assert np.abs(t_form - t_ref).max() < 0.2 * np.abs(t_ref).max()       # measured 0.15
    # where the fine grid has the source's vertices, the displacement is the source's
    V = apply_texture(Vt, Ft, res.texture)
    k = np.round(Vt[:, :2] * 32).astype(int)
    on = (k % 2 == 0).all(axis=1)
    src = (k[on, 0] // 2) * 17 + k[on, 1] // 2     # grid_plane's vertex order
    assert np.allclose(Vs[src, :2], Vt[on, :2])
    np.testing.assert_allclose(V[on] - Vt[on], (V0 - Vs)[src], atol=1e-12)


def test_sphere_is_closed_manifold_and_free_of_self_intersections(on_sphere):
    res, V = on_sphere
    topo = edge_topology(res.faces, len(V))
    assert topo.boundary.size == 0 and topo.non_manifold.size == 0
    assert len(res.vertices) > 3 * 642             # refined from icosphere(2)
    assert len(self_intersecting_pairs(V, res.faces)) == 0
    assert res.texture.metadata["fallback_edges"] == 0


def test_sphere_heights_follow_the_source_distribution(plane, on_sphere):
    *_, tex = plane
    res, _ = on_sphere
    V0, F, Vs, _ = plane
    h, hs = res.texture.height, SCALE * tex.height
    assert abs(h.max() - hs.max()) < 0.05 * hs.max()          # measured 2.7 %
    # area-weighted means (the source grid's border vertices carry less area)
    M = igl.massmatrix(res.vertices, res.faces, igl.MASSMATRIX_TYPE_VORONOI).diagonal()
    Ms = igl.massmatrix(Vs, F, igl.MASSMATRIX_TYPE_VORONOI).diagonal()
    mean, mean_s = (M * h).sum() / M.sum(), (Ms * hs).sum() / Ms.sum()
    assert abs(mean - mean_s) < 0.05 * mean_s                 # measured 0.3 %
    # the share of the surface covered by bumps is the source's
    cover, cover_s = (M * (h > 0.01)).sum() / M.sum(), (Ms * (hs > 0.01)).sum() / Ms.sum()
    assert abs(cover - cover_s) < 0.06                         # measured 0.28 vs 0.25
    # bumps are present everywhere: most charts carry some
    big = h > 0.5 * hs.max()
    assert np.unique(res.owner[big]).size > 0.5 * res.n_patches


def test_sphere_leans_follow_the_field(on_sphere):
    res, V = on_sphere
    Vr, Fr = res.vertices, res.faces
    n = base_normals(Vr, Fr)
    d = V - Vr
    tan = d - np.einsum("ij,ij->i", d, n)[:, None] * n
    fv = np.zeros_like(Vr)
    for k in range(3):
        np.add.at(fv, Fr[:, k], res.field)
    fv -= np.einsum("ij,ij->i", fv, n)[:, None] * n
    fv /= np.linalg.norm(fv, axis=1, keepdims=True)
    h = res.texture.height
    tl = np.linalg.norm(tan, axis=1)
    sel = (h > 0.3 * h.max()) & (tl > 0.2 * h)
    assert sel.sum() > 100
    ang = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", tan[sel], fv[sel]) / tl[sel],
                                       -1, 1)))
    assert np.median(ang) < 5.0                    # measured 1.0
    assert np.percentile(ang, 90) < 20.0           # measured 8.5 (near the field's poles)


def test_deterministic_and_reports_progress(plane):
    V0, F, Vs, tex = plane
    Vd, Fd = icosphere(1)
    stages = []
    a = transfer_planar(Vs, F, tex, Vd, Fd, scale=1.5, progress=stages.append)
    b = transfer_planar(Vs, F, tex, Vd, Fd, scale=1.5)
    assert np.array_equal(a.vertices, b.vertices)
    assert np.array_equal(a.texture.tilt, b.texture.tilt)
    assert np.array_equal(a.texture.height, b.texture.height)
    assert len(stages) == 6


def test_refine_methods_reach_the_target_length():
    V, F = icosphere(1)
    for method in ("remesh", "subdivide"):
        Vr, Fr = refine_base(V, F, 0.1, method=method)
        E = edge_topology(Fr, len(Vr)).edges
        mean = np.linalg.norm(Vr[E[:, 1]] - Vr[E[:, 0]], axis=1).mean()
        assert 0.5 * 0.1 < mean < 1.2 * 0.1, method
        assert edge_topology(Fr, len(Vr)).boundary.size == 0
    Vr, Fr = refine_base(V, F, 0.1, method="none")
    assert np.array_equal(Fr, F)


@pytest.mark.parametrize("kwargs, message", [
    ({"scale": 0}, "scale"),
    ({"scale": 1, "field": "sideways"}, "field"),
    ({"scale": 1, "field": np.zeros((3, 3))}, "field"),
    ({"scale": 1, "refine": "loop"}, "refine"),
    ({"scale": 1, "blend": -1}, "blend"),
    ({"scale": 1, "samples": 0}, "samples"),
])
def test_bad_arguments(plane, kwargs, message):
    V0, F, Vs, tex = plane
    Vd, Fd = icosphere(1)
    with pytest.raises(InputError, match=message):
        transfer_planar(Vs, F, tex, Vd, Fd, **kwargs)


def test_source_must_be_flat_and_face_up(plane):
    V0, F, Vs, tex = plane
    Vd, Fd = icosphere(1)
    bent = Vs.copy()
    bent[:, 2] = 0.1 * bent[:, 0] ** 2
    with pytest.raises(InputError, match="flat"):
        transfer_planar(bent, F, tex, Vd, Fd, scale=1.0)
    flipped = tex.replace(faces=F[:, ::-1], tilt=np.zeros(len(tex.tilt)))
    with pytest.raises(InputError, match=r"\+z"):
        transfer_planar(Vs, F[:, ::-1], flipped, Vd, Fd, scale=1.0)
