"""Lapped textures: texture patches, hulls, coverage, the pasting loop."""

from __future__ import annotations

import math

import numpy as np
import pytest

from geotex.errors import InputError, MissingFileError
from geotex.image import (Coverage, HullTest, alignment_errors, circle_mask, lapped_texture,
                          load_lapped, mask_from_image, points_in_polygon, sample_lattice,
                          save_lapped, segments_meet_polygon, splotch_mask, star_hull,
                          texture_patches)
from geotex.mesh.primitives import icosphere, torus
from geotex.patches.grow import grow_patch

#: Bound on the angle between a paste's mapped field direction and the texture's
#: up axis, on every pasted face of a field without singularities (degrees).
ALIGNMENT_BOUND_DEG = 5.0


def _image(seed=0, size=48):
    return (np.random.default_rng(seed).random((size, size, 3)) * 255).astype(np.uint8)


def _torus_field():
    V, F = torus(1.0, 0.35, n_major=48, n_minor=24)
    C = V[F].mean(axis=1)
    return V, F, np.c_[-C[:, 1], C[:, 0], np.zeros(len(F))]


@pytest.fixture(scope="module")
def torus_lapped():
    V, F, fld = _torus_field()
    lt = lapped_texture(V, F, texture_patches(_image()), field=fld, scale=0.7, seed=3)
    return V, F, fld, lt


# ------------------------------------------------------------------ masks and patches

def test_circle_mask_falls_off_over_the_given_width():
    a = circle_mask(40, 40, falloff=3.0, margin=1.0)
    assert a[20, 20] == 1.0 and a[0, 0] == 0.0
    y, x = np.mgrid[0:40, 0:40]
    r = np.hypot(x + 0.5 - 20, y + 0.5 - 20)
    band = (a > 0) & (a < 1)
    assert band.any()
    assert r[band].min() >= 19.0 - 3.0 - 1e-9 and r[band].max() <= 19.0 + 1e-9
    assert np.all(a[r <= 16.0 - 1e-9] == 1.0)


def test_splotch_is_fixed_irregular_and_inside_the_image():
    a = splotch_mask(64, 64)
    assert np.array_equal(a, splotch_mask(64, 64))
    assert not np.array_equal(a > 0, circle_mask(64, 64) > 0)
    assert a[0, :].max() == 0 and a[:, 0].max() == 0 and a[-1, :].max() == 0
    assert 0.3 < (a > 0).mean() < 0.75
    assert ((a > 0) & (a < 1)).any()


def test_user_mask_and_its_errors(tmp_path):
    m = np.zeros((32, 32), np.uint8)
    m[8:24, 4:28] = 255
    a = mask_from_image(m, falloff=2.0)
    assert a[16, 16] == 1.0 and a[2, 2] == 0.0 and a[8, 16] < 1.0
    with pytest.raises(InputError, match="empty"):
        mask_from_image(np.zeros((32, 32), np.uint8))
    with pytest.raises(InputError, match="empty"):
        texture_patches(_image(), mask=np.zeros((48, 48), np.uint8))
    bad = tmp_path / "broken.png"
    bad.write_bytes(b"not an image at all")
    with pytest.raises(InputError, match="cannot read the image"):
        texture_patches(bad)
    with pytest.raises(InputError, match="cannot read the image"):
        texture_patches(_image(), mask=bad)
    with pytest.raises(MissingFileError):
        texture_patches(tmp_path / "missing.png")
    with pytest.raises(InputError, match="mask must be one of"):
        texture_patches(_image(), mask="blob")


def test_patch_centre_is_opaque_and_image_alpha_multiplies():
    img = np.dstack([_image(), np.full((48, 48), 255, np.uint8)])
    img[18:30, 18:30, 3] = 0                                # a transparent hole in the middle
    (p,) = texture_patches(img, mask="circle")
    L = p.pixels_per_unit
    cx, cy = p.center * L
    assert p.rgba[int(48 - cy), int(cx), 3] >= p.opaque
    assert p.rgba[24, 24, 3] == 0.0


def test_several_patches_are_cut_at_seeded_positions():
    a = texture_patches(_image(size=64), count=3, size=32, seed=5)
    b = texture_patches(_image(size=64), count=3, size=32, seed=5)
    assert len(a) == 3 and all(p.rgba.shape == (32, 32, 4) for p in a)
    assert all(np.array_equal(x.rgba, y.rgba) for x, y in zip(a, b))
    assert not np.array_equal(a[1].rgba, a[2].rgba)
    with pytest.raises(InputError, match="count"):
        texture_patches(_image(), count=0)
    with pytest.raises(InputError, match="size"):
        texture_patches(_image(), size=100)


# ------------------------------------------------------------------ hulls

@pytest.mark.parametrize("mask", ["circle", "splotch"])
def test_star_hull_contains_every_visible_pixel_and_is_tight(mask):
    (p,) = texture_patches(_image(size=64), mask=mask)
    support = p.rgba[:, :, 3] > 0
    iy, ix = np.nonzero(support)
    L = p.pixels_per_unit
    corners = np.concatenate([np.stack([(ix + dx) / L, (64 - iy - dy) / L], 1)
                              for dx in (0, 1) for dy in (0, 1)])
    assert points_in_polygon(corners, p.hull).all()
    H = p.hull
    area = 0.5 * abs(np.sum(H[:, 0] * np.roll(H[:, 1], -1) - np.roll(H[:, 0], -1) * H[:, 1]))
    assert area < 1.25 * support.sum() / L ** 2


def test_hull_segment_test_matches_the_vectorized_test():
    (p,) = texture_patches(_image(), mask="splotch")
    ht = HullTest(p.hull, p.center)
    rng = np.random.default_rng(1)
    A = rng.uniform(-0.3, 1.3, (400, 2))
    B = A + rng.normal(0, 0.15, (400, 2))
    ref = segments_meet_polygon(A, B, p.hull)
    got = np.array([ht.segment(*a, *b) for a, b in zip(A, B)])
    assert ref.any() and (~ref).any()
    assert np.array_equal(got, ref)


# ------------------------------------------------------------------ coverage lattice

@pytest.mark.parametrize("r", [1, 2, 4, 5])
def test_sample_lattice_covers_the_face_evenly(r):
    b = sample_lattice(r)
    assert b.shape == (r * r, 3)
    assert np.allclose(b.sum(axis=1), 1.0) and (b > 0).all()
    assert np.allclose(b.mean(axis=0), 1.0 / 3.0)
    assert np.unique(np.round(b, 12), axis=0).shape[0] == r * r


def test_grow_patch_reports_each_joining_face_in_order():
    V, F = icosphere(3)
    seen = []
    p = grow_patch(V, F, 0, max_radius=0.6, on_join=seen.append)
    assert seen == p.faces.tolist()


# ------------------------------------------------------------------ the pasting loop

def test_coverage_is_complete_and_follows_from_the_records(torus_lapped):
    V, F, _, lt = torus_lapped
    assert lt.complete and lt.n_pastes > 10
    assert np.all(lt.coverage == 1.0)
    # rasterize the recorded pastes afresh: every sample of every face is opaque
    cov = Coverage(len(F), resolution=lt.metadata["samples"])
    for p in lt.pastes:
        assert p.faces.size == np.unique(p.faces).size
        cov.update(p.faces, p.corner_uv, lt.patches[p.patch])
    assert cov.complete


def test_every_paste_follows_the_field(torus_lapped):
    V, F, fld, lt = torus_lapped
    err = np.degrees(alignment_errors(V, F, lt))
    face, paste, _, _ = lt.layers()
    worst = np.zeros(lt.n_pastes)
    np.maximum.at(worst, paste, err)
    assert worst.max() < ALIGNMENT_BOUND_DEG
    # and the directions the pastes aligned to are the field's
    dirs = np.concatenate([p.directions for p in lt.pastes])
    f = fld[face] / np.linalg.norm(fld[face], axis=1)[:, None]
    assert np.einsum("ij,ij->i", dirs, f).min() > 0.999


def test_neighbouring_faces_of_a_paste_share_texture_coordinates(torus_lapped):
    V, F, _, lt = torus_lapped
    for p in lt.pastes[:20]:
        corners = F[p.faces].ravel()
        uv = p.corner_uv.reshape(-1, 2)
        order = np.argsort(corners, kind="stable")
        c, u = corners[order], uv[order]
        same = c[1:] == c[:-1]
        assert np.array_equal(u[1:][same], u[:-1][same])


def test_isotropic_pastes_follow_their_propagated_direction():
    V, F, _ = _torus_field()
    lt = lapped_texture(V, F, texture_patches(_image(), mask="circle"), scale=0.7, seed=4)
    assert lt.complete
    assert np.degrees(alignment_errors(V, F, lt)).max() < 2 * ALIGNMENT_BOUND_DEG
    seeds = np.array([p.directions[0] for p in lt.pastes])
    assert np.abs(seeds @ seeds[0]).min() < 0.5            # random orientations


def test_line_fields_are_combed_inside_each_paste():
    V, F, fld = _torus_field()
    flips = np.where(np.random.default_rng(2).random(len(F)) < 0.5, -1.0, 1.0)
    lt = lapped_texture(V, F, texture_patches(_image()), field=fld * flips[:, None],
                        symmetry=2, scale=0.7, seed=3)
    assert lt.complete
    assert np.degrees(alignment_errors(V, F, lt)).max() < ALIGNMENT_BOUND_DEG


def test_same_seed_gives_the_same_bytes(tmp_path):
    V, F = icosphere(2)
    pt = texture_patches(_image())
    a = lapped_texture(V, F, pt, scale=0.9, seed=11)
    b = lapped_texture(V, F, pt, scale=0.9, seed=11)
    c = lapped_texture(V, F, pt, scale=0.9, seed=12)
    save_lapped(tmp_path / "a.npz", a)
    save_lapped(tmp_path / "b.npz", b)
    save_lapped(tmp_path / "c.npz", c)
    assert (tmp_path / "a.npz").read_bytes() == (tmp_path / "b.npz").read_bytes()
    assert (tmp_path / "a.npz").read_bytes() != (tmp_path / "c.npz").read_bytes()
    back = load_lapped(tmp_path / "a.npz")
    assert back.n_pastes == a.n_pastes and back.complete
    for x, y in zip(back.pastes, a.pastes):
        assert np.array_equal(x.faces, y.faces) and np.array_equal(x.corner_uv, y.corner_uv)
    assert np.array_equal(back.patches[0].rgba, a.patches[0].rgba)


def test_larger_scale_needs_fewer_pastes():
    V, F = icosphere(3)
    pt = texture_patches(_image())
    small = lapped_texture(V, F, pt, scale=0.6, seed=1)
    large = lapped_texture(V, F, pt, scale=1.2, seed=1)
    assert small.complete and large.complete
    assert large.n_pastes < small.n_pastes
    assert np.mean([p.n_faces for p in large.pastes]) > np.mean([p.n_faces for p in small.pastes])


def test_lapped_texture_errors():
    V, F = icosphere(1)
    pt = texture_patches(_image())
    with pytest.raises(InputError, match="field must have one vector per face"):
        lapped_texture(V, F, pt, field=np.ones((3, 3)))
    with pytest.raises(InputError, match="scale"):
        lapped_texture(V, F, pt, scale=-1.0)
    with pytest.raises(InputError, match="smaller than the mean edge length"):
        lapped_texture(V, F, pt, scale=0.01)
    with pytest.raises(InputError, match="TexturePatch"):
        lapped_texture(V, F, [])
    with pytest.raises(InputError, match="symmetry"):
        lapped_texture(V, F, pt, field=V[F].mean(1) * 0 + [0, 0, 1.0], symmetry=3, scale=1.0)
    Vd = np.vstack([V, V[0]])
    Fd = np.vstack([F, [[0, 1, len(V)]]])
    with pytest.raises(InputError, match="degenerate"):
        lapped_texture(Vd, Fd, pt, scale=1.0)
    normal = V[F].mean(axis=1)                               # radial: normal to the sphere
    with pytest.raises(InputError, match="normal to the surface"):
        lapped_texture(V, F, pt, field=normal, scale=1.0)


def test_max_pastes_stops_early_and_says_incomplete():
    V, F = icosphere(3)
    lt = lapped_texture(V, F, texture_patches(_image()), scale=0.5, seed=0, max_pastes=3)
    assert lt.n_pastes == 3 and not lt.complete
    assert math.isclose(lt.coverage.max(), 1.0)


def test_placement_priority_marks_singularities_and_bends():
    from geotex.fields.directions import projected_direction_field
    from geotex.image import placement_priority
    from geotex.mesh.primitives import grid_plane

    V, F = grid_plane(6, 6)
    flat = placement_priority(V, F, up=np.tile([1.0, 0.0, 0.0], (len(F), 1)), scale=0.5)
    assert np.all(flat == 0.0)
    V, F = icosphere(3)
    up, _ = projected_direction_field(V, F, [0.0, 0.0, 1.0])
    p = placement_priority(V, F, up=up, scale=0.5)
    assert p.min() >= 0.0 and p.max() <= 1.0
    top = np.argmax(V[:, 2])
    assert np.all(p[np.isin(F, top).any(axis=1)] == 1.0)   # the pole is a singularity
    assert np.median(p) < 0.5


def test_on_paste_reports_progress():
    V, F = icosphere(2)
    calls = []
    lt = lapped_texture(V, F, texture_patches(_image()), scale=0.9, seed=0,
                        on_paste=lambda n, covered, total: calls.append((n, covered, total)))
    assert [c[0] for c in calls] == list(range(1, lt.n_pastes + 1))
    assert calls[-1][1] == calls[-1][2] == len(F)
    assert all(a[1] <= b[1] for a, b in zip(calls, calls[1:]))


def test_later_pastes_lie_on_top():
    from geotex.image import LappedTexture, Paste, composite_at

    V, F = icosphere(1)
    red = np.zeros((16, 16, 3), np.uint8)
    red[..., 0] = 255
    blue = np.zeros((16, 16, 3), np.uint8)
    blue[..., 2] = 255
    (pr,) = texture_patches(red, mask="circle", falloff=0)
    (pb,) = texture_patches(blue, mask="circle", falloff=0)
    uv = np.tile(pr.center, (1, 3, 1))                       # the face maps to the centre
    paste = [Paste(patch=k, faces=np.array([0]), corner_uv=uv, directions=np.zeros((1, 3)),
                   seed_point=np.zeros(3)) for k in (0, 1)]
    lt = LappedTexture(pastes=tuple(paste), patches=(pr, pb), n_vertices=len(V),
                       n_faces=len(F), coverage=np.ones(len(F)), metadata={})
    c = composite_at(lt, [0, 1], [[1 / 3, 1 / 3, 1 / 3]] * 2)
    assert np.allclose(c[0], [0, 0, 1, 1], atol=1e-6)        # blue, pasted last
    assert np.allclose(c[1, 3], 0.0)                         # face 1: no paste, background


def _uncovered_inner_hull(lt):
    """Per interior paste: fraction of the margin-shrunk hull outside its uv image."""
    from geotex.image.paste import REGROW_MARGIN

    p0 = lt.patches[0]
    inner = p0.center + (1 - REGROW_MARGIN) * (p0.hull - p0.center)
    g = np.stack(np.meshgrid(np.linspace(0, 1, 41), np.linspace(0, 1, 41)), -1).reshape(-1, 2)
    g = g[points_in_polygon(g, inner)][:, None, :]
    out = []
    for p in lt.pastes:
        if not np.all((p.seed_point[:2] > 1.0) & (p.seed_point[:2] < 3.0)):
            continue                                         # near the plane's border
        A, B, C = (p.corner_uv[None, :, k] for k in range(3))

        def cross(o, a, b):
            return ((a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1])
                    - (a[..., 1] - o[..., 1]) * (b[..., 0] - o[..., 0]))

        d = np.stack([cross(A, B, g), cross(B, C, g), cross(C, A, g)])
        inside = (d >= 0).all(axis=0) | (d <= 0).all(axis=0)
        out.append(1.0 - inside.any(axis=1).mean())
    return np.array(out)


def test_regrowing_covers_what_the_optimization_uncovered():
    from geotex.mesh.primitives import grid_plane

    V, F = grid_plane(40, 40, size=(4, 4))
    angle = 2.0 * V[F].mean(axis=1)[:, 0]                 # a field turning along x (curl)
    fld = np.c_[np.cos(angle), np.sin(angle), np.zeros(len(F))]
    pt = texture_patches(_image())
    once = lapped_texture(V, F, pt, field=fld, scale=1.0, seed=3, rounds=1)
    again = lapped_texture(V, F, pt, field=fld, scale=1.0, seed=3, rounds=2)
    assert once.complete and again.complete
    assert any(p.rounds == 2 for p in again.pastes)
    u1, u2 = _uncovered_inner_hull(once), _uncovered_inner_hull(again)
    assert u1.size > 5 and u2.size > 5
    assert u1.max() > 0.0 and u2.max() == 0.0
