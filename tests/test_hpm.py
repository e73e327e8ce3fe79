"""Hierarchical pattern mapping: cluster hierarchy, barycentric flattening, FFT fitting, CLI."""

import json

import numpy as np
import pytest
from scipy.spatial import Delaunay

from geotex.cli import main
from geotex.errors import InputError
from geotex.image.fftmatch import (brute_force_energy, match_energy, opponent_colors,
                                   pattern_scale, texture_spectra)
from geotex.image.hpm import hpm_mesh, hpm_texture
from geotex.io import read_mesh, write_mesh
from geotex.mesh import edge_topology, face_areas
from geotex.mesh.primitives import box, grid_plane, icosphere, torus
from geotex.mesh.record import Mesh
from geotex.patches import cluster_hierarchy, is_disc_partition
from geotex.patches.clusters import ALIGNMENT_RATIO
from geotex.patches.flatten import (barycentric_hierarchy, cluster_frames, control_polygon,
                                    flatten_cluster)


def jittered_disc(n=300, seed=0):
    rng = np.random.default_rng(seed)
    pts = np.vstack([rng.uniform(-1, 1, (n, 2)), [[-1, -1], [1, -1], [1, 1], [-1, 1]]])
    F = Delaunay(pts).simplices.astype(np.int64)
    a, b, c = pts[F[:, 0]], pts[F[:, 1]], pts[F[:, 2]]
    neg = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]) < 0
    F[neg] = F[neg][:, ::-1]
    return np.column_stack([pts, np.zeros(len(pts))]), F


MESHES = {
    "sphere": lambda: icosphere(3),
    "torus": lambda: torus(1.0, 0.35, n_major=32, n_minor=16),
    "box": lambda: box(divisions=4),
    "jittered": lambda: jittered_disc(300, seed=1),
}


def noise_image(h=64, w=64, seed=0):
    """Smooth coloured noise, uint8 (a stand-in for a photo texture)."""
    rng = np.random.default_rng(seed)
    x = rng.random((h // 8 + 2, w // 8 + 2, 3))
    from scipy.ndimage import zoom
    img = zoom(x, (8, 8, 1), order=3)[:h, :w]
    img = (img - img.min()) / (np.ptp(img) + 1e-12)
    return (img * 255).astype(np.uint8)


# ---------------------------------------------------------------------------
# hierarchy
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("name", sorted(MESHES))
def test_hierarchy_invariants(name):
    V, F = MESHES[name]()
    H = cluster_hierarchy(V, F)
    m, n = len(F), len(V)
    assert len(H) >= 3
    A = face_areas(V, F)
    t = edge_topology(F, n)
    border = np.zeros(n, bool)
    border[t.edges[t.face_count != 2].ravel()] = True
    # top: the whole surface; bottom: single faces
    assert H[0].n_clusters == 1 and np.all(H[0].labels == 0)
    last = H[-1]
    assert last.n_clusters == m and np.unique(last.labels).size == m
    prev = None
    for li, lv in enumerate(H.levels):
        lab = lv.labels
        assert lab.min() == 0 and lab.max() == lv.n_clusters - 1
        assert np.unique(lab).size == lv.n_clusters                  # partition, all used
        assert np.allclose(lv.area, np.bincount(lab, weights=A))
        if li >= 1:
            assert is_disc_partition(F, lab) and lv.disc.all()
            assert np.array_equal(lv.parent[lab], prev.labels)       # nested in the parent
            assert np.all(np.diff(lv.parent) >= 0)                   # children contiguous
            assert np.array_equal(prev.child_ptr, np.searchsorted(lv.parent,
                                                                  np.arange(prev.n_clusters + 1)))
        if 1 <= li < len(H) - 1:
            assert lv.n_clusters > prev.n_clusters
        for c in range(lv.n_clusters) if li >= 1 else []:
            loop = lv.boundary_loop(c)
            ctrl = lv.controls(c)
            assert len(ctrl) >= 3
            # borders are mesh edges: the loop is the cluster's boundary cycle
            sub = F[lab == c]
            st = edge_topology(sub, n)
            bnd = {tuple(e) for e in st.edges[st.face_count == 1].tolist()}
            lp = loop.tolist()
            assert len(lp) == len(bnd) == len(set(lp))
            assert {tuple(sorted((lp[i], lp[(i + 1) % len(lp)]))) for i in range(len(lp))} == bnd
            # control vertices lie on the loop, in loop order
            where = [lp.index(v) for v in ctrl.tolist()]
            assert where == sorted(where)
            js = lv.control_is_junction[lv.control_ptr[c]:lv.control_ptr[c + 1]]
            assert np.all(lv.junction[ctrl[js]])
            # non-alignment: the control points span a plane (or every loop vertex is used)
            P = V[ctrl] - V[ctrl].mean(axis=0)
            s = np.linalg.svd(P, compute_uv=False)
            assert s[1] >= ALIGNMENT_RATIO * s[0] - 1e-12 or len(ctrl) == len(loop)
        prev = lv
    # junctions: vertices where >= 3 regions meet (the outside counts as one)
    lv = H[2]
    reg = [set() for _ in range(n)]
    for f, tri in enumerate(F.tolist()):
        for v in tri:
            reg[v].add(int(lv.labels[f]))
    nreg = np.array([len(r) for r in reg]) + border
    assert np.array_equal(lv.junction, nreg >= 3)


def test_hierarchy_genus_two_and_descendants():
    from geotex.mesh.primitives import plate_with_holes
    V, F = plate_with_holes(2)
    H = cluster_hierarchy(V, F)
    for lv in H.levels[1:]:
        assert is_disc_partition(F, lv.labels)
    lo, hi = H.descendants(1, 0, len(H) - 1)
    faces = np.flatnonzero((H[-1].labels >= lo) & (H[-1].labels < hi))
    assert np.array_equal(np.sort(faces), H[1].faces(0))


def test_hierarchy_deterministic_pure_and_seeded():
    V, F = torus(1.0, 0.35, n_major=32, n_minor=16)
    V0, F0 = V.copy(), F.copy()
    a = cluster_hierarchy(V, F, seed=3)
    b = cluster_hierarchy(V, F, seed=3)
    c = cluster_hierarchy(V, F, seed=4)
    assert np.array_equal(V, V0) and np.array_equal(F, F0)
    assert all(np.array_equal(x.labels, y.labels) and
               np.array_equal(x.control_vertices, y.control_vertices)
               for x, y in zip(a.levels, b.levels))
    assert any(not np.array_equal(x.labels, y.labels) for x, y in zip(a.levels, c.levels))


def test_hierarchy_finest_cluster_level_is_a_few_faces():
    # 4992 faces: 6^4 clusters would be under 4 faces each, so the branching stops at
    # 6^3 = 216 clusters of ~23 faces; one more split to ~4 faces follows (a cluster
    # refused there leaves only a few faces to the face level)
    V, F = torus(1.0, 0.4, n_major=96, n_minor=26)
    H = cluster_hierarchy(V, F)
    assert len(F) / H[-2].n_clusters <= 2 * 4
    assert H[-3].n_clusters < H[-2].n_clusters < len(F)
    assert is_disc_partition(F, H[-2].labels)
    # a level already small enough is not split again
    V, F = icosphere(3)
    sizes = [len(F) / lv.n_clusters for lv in cluster_hierarchy(V, F).levels[:-1]]
    assert sizes[-1] <= 8 and sizes[-2] > 8


def test_hierarchy_errors():
    V, F = icosphere(2)
    with pytest.raises(InputError, match="branching"):
        cluster_hierarchy(V, F, branching=1.0)
    with pytest.raises(InputError, match="leaf_faces"):
        cluster_hierarchy(V, F, leaf_faces=0)
    flipped = F.copy()
    flipped[0] = flipped[0, ::-1]
    with pytest.raises(InputError, match="oriented"):
        cluster_hierarchy(V, flipped)
    with pytest.raises(InputError, match="empty"):
        cluster_hierarchy(V, np.zeros((0, 3), np.int64))


# ---------------------------------------------------------------------------
# barycentric flattening
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("coordinates", ["mean_value", "stable_base"])
def test_flattening_is_exact_on_a_plane(coordinates):
    V, F = jittered_disc(200, seed=2)
    H = cluster_hierarchy(V, F)
    bh = barycentric_hierarchy(V, F, H, coordinates=coordinates)
    for li in range(len(H) - 1):
        N, e1, e2 = cluster_frames(V, F, H[li].labels, H[li].n_clusters)
        for c in range(min(4, H[li].n_clusters)):
            poly = control_polygon(V, H[li].controls(c), e1[c], e2[c])
            verts, uv, faces = flatten_cluster(bh, li, c, poly)
            assert np.array_equal(np.sort(faces), H[li].faces(c))
            q = np.stack([V[verts] @ e1[c], V[verts] @ e2[c]], axis=1)
            assert np.abs(uv - q).max() < 1e-9


def test_mean_value_flattening_folds_fewer_clusters_than_the_stable_base():
    # a fine torus: the stable base (three parent corners per vertex) switches corners
    # between neighbouring vertices and the map jumps there, longer than the edges;
    # mean value coordinates are smooth (here 1 folded cluster of 36 against 4)
    V, F = torus(1.0, 0.35, n_major=96, n_minor=48)
    H = cluster_hierarchy(V, F, seed=0)
    folds = {}
    for mode in ("mean_value", "stable_base"):
        bh = barycentric_hierarchy(V, F, H, coordinates=mode)
        n = 0
        for li in (2,):
            N, e1, e2 = cluster_frames(V, F, H[li].labels, H[li].n_clusters)
            for c in range(H[li].n_clusters):
                poly = control_polygon(V, H[li].controls(c), e1[c], e2[c])
                verts, uv, faces = flatten_cluster(bh, li, c, poly)
                U = np.zeros((len(V), 2))
                U[verts] = uv
                t = U[F[faces]]
                d = (t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1]) \
                    - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0])
                n += bool((d <= 0).any())
        folds[mode] = n
    assert folds["mean_value"] < folds["stable_base"]
    with pytest.raises(InputError, match="coordinates"):
        barycentric_hierarchy(V, F, H, coordinates="harmonic")


def test_flattening_fixed_vertices_are_kept_and_spread():
    V, F = icosphere(3)
    H = cluster_hierarchy(V, F)
    bh = barycentric_hierarchy(V, F, H)
    N, e1, e2 = cluster_frames(V, F, H[2].labels, H[2].n_clusters)
    poly = control_polygon(V, H[2].controls(0), e1[0], e2[0])
    verts, uv, _ = flatten_cluster(bh, 2, 0, poly)
    fixed = np.zeros((len(V), 2))
    mask = np.zeros(len(V), bool)
    v0 = H[2].boundary_loop(0)[:3]
    mask[v0] = True
    fixed[verts] = uv
    fixed[v0] += 0.01
    verts2, uv2, _ = flatten_cluster(bh, 2, 0, poly, fixed=fixed, fixed_mask=mask)
    k = np.searchsorted(verts2, v0)
    assert np.allclose(uv2[k], fixed[v0])
    moved = np.linalg.norm(uv2 - uv, axis=1)
    assert (moved > 1e-6).sum() > 3                 # the change spreads past the fixed ones


# ---------------------------------------------------------------------------
# FFT matching
# ---------------------------------------------------------------------------

def test_fft_energy_equals_brute_force():
    rng = np.random.default_rng(0)
    T = opponent_colors(rng.random((24, 20, 3)))
    spectra = texture_spectra(T, orientations=1)
    h, w = T.shape[:2]
    J = np.zeros((h, w))
    J[1:6, 2:8] = (rng.random((5, 6)) > 0.3)
    I = rng.random((h, w, 3)) * J[:, :, None]
    K = J.copy()
    E = match_energy(spectra, I, J, K)[0]
    checked = 0
    for dy in range(h):
        for dx in range(w):
            if np.isfinite(E[dy, dx]):
                # single-precision FFT: agreement to 1e-5 of the mask's energy scale
                assert E[dy, dx] == pytest.approx(brute_force_energy(T, I, J, dy, dx),
                                                  abs=1e-5 * float(np.sum(I * I) + J.sum()))
                checked += 1
    assert checked > 100
    # positions where the footprint would leave the image are refused
    ys, xs = np.nonzero(K)
    assert np.all(~np.isfinite(E[h - ys.max():, :])) and np.all(~np.isfinite(E[:, w - xs.max():]))


def test_mask_spectra_equal_rfft2_of_each_plane():
    # the row-pruned transform of the mask and its support (one call, rows of the
    # support only) gives the values of rfft2 per plane, for bands anywhere, empty too
    import scipy.fft as sfft

    from geotex.image import fftmatch
    rng = np.random.default_rng(5)
    for h, w, r0, r1 in ((24, 30, 3, 9), (24, 30, 0, 24), (17, 16, 16, 17), (20, 20, 5, 5)):
        J = np.zeros((h, w))
        J[r0:r1] = rng.random((r1 - r0, w)) > 0.4
        I = rng.random((h, w, 3)) * J[:, :, None]
        fI, fJ = fftmatch._mask_spectra(I, J)
        assert np.array_equal(fI, np.conj(sfft.rfft2(np.moveaxis(I, 2, 0).astype(np.float32),
                                                     axes=(-2, -1))))
        assert np.array_equal(fJ, np.conj(sfft.rfft2(J.astype(np.float32))))


def test_compiled_energy_assembly_gives_the_same_bytes():
    rng = np.random.default_rng(6)
    T = opponent_colors(rng.random((30, 26, 3)))
    spectra = texture_spectra(T, orientations=7)
    J = np.zeros((30, 26))
    J[4:11, 3:12] = rng.random((7, 9)) > 0.3
    I = rng.random((30, 26, 3)) * J[:, :, None]
    K = J.copy()
    K[8:14, 6:15] = 1.0
    pixels = np.concatenate([np.flatnonzero(J), np.flatnonzero(K)])     # repeats, any order
    for which in (None, [2], [0, 4]):
        E = match_energy(spectra, I, J, K, which=which)
        assert np.isfinite(E).any() and not np.isfinite(E).all()
        assert match_energy(spectra, I, J, K, which=which, fast=True).tobytes() == E.tobytes()
        # the footprint's pixels given instead of scanned: the same bytes
        assert match_energy(spectra, I, J, K, which=which, fast=True,
                            footprint_pixels=pixels[::-1]).tobytes() == E.tobytes()


def test_bilinear_lookup_equals_map_coordinates():
    # the matcher's bilinear lookup (pixel centres at +0.5, clamped to the border) is
    # scipy's order-1 interpolation with mode "nearest", on every channel, for points
    # inside, on the border and far outside, on square and non-square images
    from scipy.ndimage import map_coordinates

    from geotex.image import hpm_kernels
    rng = np.random.default_rng(3)
    for h, w in ((17, 23), (9, 9), (2, 5)):
        img = rng.random((h, w, 3))
        xy = np.column_stack([rng.uniform(-4, w + 4, 400), rng.uniform(-4, h + 4, 400)])
        xy[:8] = [[0.5, 0.5], [w - 0.5, h - 0.5], [w, h], [0, 0], [w - 0.5, 0.5],
                  [0.5, h - 0.5], [w / 2, h - 0.5], [w - 1e-9, 1.0]]
        got = hpm_kernels._sample(img, xy)
        ref = np.stack([map_coordinates(img[:, :, k], [xy[:, 1] - 0.5, xy[:, 0] - 0.5],
                                        order=1, mode="nearest") for k in range(3)], 1)
        assert got.shape == (400, 3)
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12)


def checker_image(cell=8, n=96, seed=0):
    """A grey checkerboard of ``cell``-pixel squares with a little noise, uint8."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:n, 0:n]
    img = np.where(((xx // cell) + (yy // cell)) % 2 == 0, 200.0, 60.0)
    img += rng.normal(0.0, 10.0, img.shape)
    return np.repeat(np.clip(img, 0, 255).astype(np.uint8)[:, :, None], 3, axis=2)


@pytest.mark.parametrize("cell", [6, 8, 11])
def test_pattern_scale_of_a_checker_and_of_stripes(cell):
    # a checker of cell c is a lattice of period vectors (c, c) and (c, -c)
    ps = pattern_scale(checker_image(cell))
    assert ps.periodic and ps.periods.shape == (2, 2)
    assert ps.period == pytest.approx(cell * np.sqrt(2.0), abs=0.01)
    assert np.allclose(np.sort(np.abs(ps.periods), axis=None), cell)
    assert ps.coherence < 0.1                     # isotropic
    # stripes of period p: one repeat, across them; strongly anisotropic, along x
    p = cell + 3
    yy = np.arange(96)[:, None] * np.ones((1, 96))
    img = (127 + 100 * np.sin(2 * np.pi * yy / p)).astype(np.uint8)
    ps = pattern_scale(img)
    assert ps.periodic and ps.periods.shape == (1, 2)
    assert ps.period == pytest.approx(p, abs=0.51)
    assert ps.coherence > 0.9
    assert min(ps.orientation, np.pi - ps.orientation) < 0.05


def dot_lattice_image(u, v, n=128, sigma=2.5, seed=0):
    """Grey Gaussian dots at the lattice points ``i u + j v`` with a little noise, uint8."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:n, 0:n].astype(np.float64)
    img = np.zeros((n, n))
    u, v = np.asarray(u, float), np.asarray(v, float)
    for i in range(-20, 21):
        for j in range(-8, 9):
            c = 5.0 + i * u + j * v
            if -10 <= c[0] <= n + 10 and -10 <= c[1] <= n + 10:
                img += np.exp(-((xx - c[0]) ** 2 + (yy - c[1]) ** 2) / (2 * sigma ** 2))
    img = 40 + 180 * img / img.max() + rng.normal(0.0, 4.0, img.shape)
    return np.repeat(np.clip(img, 0, 255).astype(np.uint8)[:, :, None], 3, axis=2)


def test_pattern_scale_finds_a_repeat_longer_than_a_quarter_of_the_image():
    # rows of dots 14 px apart along (14, 3), rows repeating along (-3, 40): the second
    # repeat is beyond a quarter of the 128 px image (32 px), where it cannot be confirmed
    # at twice its length; it is accepted because the lattice holds at v + u or v - u
    u, v = np.array([14.0, 3.0]), np.array([-3.0, 40.0])
    ps = pattern_scale(dot_lattice_image(u, v))
    assert ps.periodic and ps.periods.shape == (2, 2)
    basis = np.array([u, v])
    coef = np.linalg.solve(basis.T, ps.periods.T).T       # the repeats in the true basis
    assert np.allclose(coef, np.rint(coef), atol=0.1)
    assert abs(np.linalg.det(ps.periods)) == pytest.approx(abs(np.linalg.det(basis)), rel=0.05)
    assert ps.period == pytest.approx(np.linalg.norm(v), abs=1.5)
    # the stripes of the test above keep a single repeat (ridges are not lattice peaks)
    yy = np.arange(128)[:, None] * np.ones((1, 128))
    ps = pattern_scale((127 + 100 * np.sin(2 * np.pi * yy / 15)).astype(np.uint8))
    assert ps.periods.shape == (1, 2)


def test_pattern_scale_of_noise_is_its_correlation_length():
    # smooth noise (features of about 8 px): no repeat, a short correlation length
    for seed in range(3):
        ps = pattern_scale(noise_image(96, 96, seed=seed))
        assert not ps.periodic and ps.period == 0.0 and ps.periods.shape == (0, 2)
        assert 1.0 <= ps.correlation_length <= 8.0
        assert ps.size == ps.correlation_length
    with pytest.raises(InputError):
        pattern_scale(np.zeros((4, 4, 3)))


def test_fft_match_finds_a_planted_patch_and_its_rotation():
    img = noise_image(64, 64, seed=5).astype(np.float64) / 255.0
    T = opponent_colors(img)
    spectra = texture_spectra(T, orientations=8)
    h, w = T.shape[:2]
    J = np.zeros((h, w))
    J[:12, :12] = 1.0
    k = 3
    R = spectra.rotated[k]
    I = np.zeros((h, w, 3))
    I[:12, :12] = R[30:42, 25:37]
    E = match_energy(spectra, I, J, J)
    kk, dy, dx = np.unravel_index(np.argmin(E), E.shape)
    assert (kk, dy, dx) == (k, 30, 25)
    assert E[kk, dy, dx] < 1e-4


# ---------------------------------------------------------------------------
# the mapping
# ---------------------------------------------------------------------------

@pytest.fixture(scope="module")
def mapped():
    V, F = icosphere(3)
    img = noise_image(64, 64)
    r = hpm_texture(V, F, img, scale=3.0, seed=1)
    return V, F, img, r


def test_hpm_covers_every_face_with_finite_uv(mapped):
    V, F, img, r = mapped
    assert r.uv_faces.shape == F.shape and np.isfinite(r.uv).all()
    assert r.uv_faces.max() == r.uv.shape[0] - 1
    rep = r.report()
    placed = sum(lv["placed"] for lv in rep["levels"])
    assert placed == rep["placements"] >= 2
    assert sum(lv["filled_faces"] for lv in rep["levels"]) == np.count_nonzero(r.patch < 0)
    # placed patches stay inside the image (it is not treated as toroidal)
    ok = r.patch[np.arange(len(F))] >= 0
    uvp = r.uv[r.uv_faces[ok]].reshape(-1, 2)
    assert uvp.min() >= -0.02 and uvp.max() <= 1.02
    errs = [lv["mean_error"] for lv in rep["levels"] if lv["mean_error"] is not None]
    assert errs and all(0 <= e <= 0.35 for e in errs)


def test_hpm_uv_continuous_within_clusters(mapped):
    V, F, img, r = mapped
    # every vertex has one texture coordinate per placement around it
    for p in np.unique(r.patch[r.patch >= 0]):
        fs = np.flatnonzero(r.patch == p)
        pairs = np.unique(np.column_stack([F[fs].ravel(), r.uv_faces[fs].ravel()]), axis=0)
        assert np.unique(pairs[:, 0]).size == pairs.shape[0]
    # vertices are split only where the mapping jumps: fewer uv than corners
    assert len(V) <= r.uv.shape[0] < 3 * len(F)


def test_hpm_fills_few_faces_at_face_level():
    # a small scale on a 5k-face torus: clusters of ~23 faces are too large for the
    # image or match badly; they must be retried as smaller patches, not left to the
    # per-face gap filling (47 % of the faces were, when the level of ~23 faces was
    # followed by single faces)
    V, F = torus(1.0, 0.4, n_major=96, n_minor=26)
    r = hpm_texture(V, F, noise_image(64, 64), scale=0.5, seed=1)
    filled = np.count_nonzero(r.patch < 0)
    assert filled <= 0.01 * len(F)
    rep = r.report()["levels"]
    assert rep[-1]["filled_faces"] == filled
    coarse, fine = rep[-3], rep[-2]
    assert coarse["refused"].get("too_large", 0) > 0 and fine["placed"] > 0
    assert sum(sum(lv["refused"].values()) for lv in rep) >= coarse["subdivided"]


@pytest.mark.parametrize("snap", [1.5, 3.0])
def test_hpm_snapping_never_flips_a_face(snap):
    # snapping a border vertex onto the neighbour's coordinates moves it by up to
    # ``snap`` pixels, a good part of a short edge: it reversed 12 faces here (62 with
    # snap=3) before the snapping kept the vertices of faces it would fold
    V, F = torus(1.0, 0.4, n_major=96, n_minor=26)
    r = hpm_texture(V, F, noise_image(64, 64), scale=3.0, seed=1, snap=snap)
    t = r.uv[r.uv_faces]
    a = (t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1]) \
        - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0])
    assert np.count_nonzero(a <= 0) == 0


def stripe_image(h=64, w=64, seed=0):
    """Coloured noise crossed by dark horizontal stripes (an anisotropic texture)."""
    img = noise_image(h, w, seed).astype(np.float64)
    img[np.sin(2 * np.pi * np.arange(h) / 8) > 0.6] *= 0.25
    return img.astype(np.uint8)


def border_rotation(V, F, r):
    """Rotation (degrees) between the two sides' texture maps at every patch border edge."""
    topo = edge_topology(F, len(V))
    two = topo.face_count == 2
    ef, ed = topo.edge_faces()[two], topo.edges[two]

    def edge_uv(f):
        ia = np.argmax(F[f] == ed[:, :1], axis=1)
        ib = np.argmax(F[f] == ed[:, 1:], axis=1)
        return r.uv[r.uv_faces[f, ib]] - r.uv[r.uv_faces[f, ia]]

    u0, u1 = edge_uv(ef[:, 0]), edge_uv(ef[:, 1])
    ang = np.degrees(np.abs(np.arctan2(u0[:, 0] * u1[:, 1] - u0[:, 1] * u1[:, 0],
                                       np.sum(u0 * u1, axis=1))))
    p0, p1 = r.patch[ef[:, 0]], r.patch[ef[:, 1]]
    return ang[(p0 != p1) & (p0 >= 0) & (p1 >= 0)]


def test_hpm_orientation_propagates_from_the_neighbours():
    # stripes: with every orientation free, a patch turned by 90 or 180 degrees
    # matches the thin band about as well, and the stripes change direction at
    # borders (median 46 degrees here); searching near the main neighbour's
    # orientation keeps them coherent
    V, F = torus(1.0, 0.4, n_major=96, n_minor=26)
    img = stripe_image()
    # (structure=False: the periodic image's lattice continuations would hide the effect)
    free = border_rotation(V, F, hpm_texture(V, F, img, scale=2.0, seed=1, structure=False,
                                             orientation_spread=None))
    kept = border_rotation(V, F, hpm_texture(V, F, img, scale=2.0, seed=1, structure=False))
    assert free.size and kept.size
    assert np.median(kept) < 0.5 * np.median(free)
    assert np.quantile(kept, 0.75) < 60.0
    with pytest.raises(InputError, match="orientation_spread"):
        hpm_texture(V, F, img, scale=2.0, orientation_spread=-5.0)


def test_hpm_periodic_stripes_keep_their_orientation():
    # stripes of period 8 px: the pattern estimate makes the band half a period wide at
    # least, continues the neighbours by whole periods and keeps clusters of a few faces
    # whole; the stripes' rotation across patch borders halves (median 14.4 -> 7.8
    # degrees here) and no face is left to unfold
    V, F = torus(1.0, 0.4, n_major=96, n_minor=26)
    img = stripe_image()
    scale = 2.0
    off = hpm_texture(V, F, img, scale=scale, seed=1, structure=False)
    on = hpm_texture(V, F, img, scale=scale, seed=1)
    pat = on.report()["pattern"]
    assert pat["periodic"] and pat["period_px"] == pytest.approx(8.0, abs=0.6)
    period = pat["period_px"] * scale / img.shape[1]
    assert pat["min_patch"] == pytest.approx(0.3 * period)
    assert pat["band_width"] >= 0.5 * period - 1e-12
    assert pat["band_width"] > off.report()["pattern"]["band_width"]
    levels = on.report()["levels"]
    assert sum(lv["forced"] for lv in levels) > 0
    assert np.count_nonzero(on.patch < 0) <= 0.002 * len(F)
    r_on, r_off = border_rotation(V, F, on), border_rotation(V, F, off)
    assert np.median(r_on) < 0.7 * np.median(r_off)
    assert np.quantile(r_on, 0.75) < np.quantile(r_off, 0.75)


def lattice_residual(F, r, img, periods):
    """Per vertex with several uv: distance (pixels) of the uv difference to the lattice.

    With one repeat (stripes), only the part across the stripes counts.
    """
    P = np.column_stack([r.uv[:, 0] * img.shape[1], (1 - r.uv[:, 1]) * img.shape[0]])
    key = np.unique(np.column_stack([F.ravel(), r.uv_faces.ravel()]), axis=0)
    s = np.flatnonzero(np.diff(key[:, 0]) == 0)
    d = P[key[s + 1, 1]] - P[key[s, 1]]
    per = np.asarray(periods, float)
    if per.shape[0] == 1:
        t = d @ per[0] / (per[0] @ per[0])
        return np.abs(t - np.rint(t)) * np.linalg.norm(per[0])
    c = np.linalg.solve(per.T, d.T).T
    return np.linalg.norm((c - np.rint(c)) @ per, axis=1)


@pytest.mark.parametrize("image", ["checker", "stripes"])
def test_hpm_lattice_snapping_keeps_the_phase_across_borders(image, monkeypatch):
    # a periodic sample: border vertices near a copy of the neighbour's texture position
    # moved by whole periods take that copy, so where the map jumps it jumps by a lattice
    # vector (across the stripes only, for stripes)
    import geotex.image.hpm as hpm
    V, F = torus(1.0, 0.4, n_major=64, n_minor=20)
    img = checker_image(8, 64) if image == "checker" else stripe_image()
    per = pattern_scale(img).periods
    on = hpm_texture(V, F, img, scale=2.0, seed=1)
    assert sum(lv["lattice_snapped"] for lv in on.report()["levels"]) > 0
    monkeypatch.setattr(hpm, "LATTICE_SNAP", 0.0)
    off = hpm_texture(V, F, img, scale=2.0, seed=1)
    assert sum(lv["lattice_snapped"] for lv in off.report()["levels"]) == 0
    r_on, r_off = lattice_residual(F, on, img, per), lattice_residual(F, off, img, per)
    assert r_on.size and r_off.size
    # share of the map's jumps that keep the phase (within 0.05 of the shortest period):
    # checker 0.18 -> 0.37 (neighbours' orientation), 0.20 -> 0.28 with the automatic
    # cross field (snaps that turn a patch by more than FIELD_SNAP_TURN are undone);
    # stripes (8 px: the tolerance is one pixel) 0.29 -> 0.34 here
    tol = 0.05 * np.linalg.norm(per, axis=1).min()
    assert np.mean(r_on < tol) > np.mean(r_off < tol) + (0.05 if image == "checker" else 0.02)
    t = on.uv[on.uv_faces]
    a = (t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1]) \
        - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0])
    assert np.count_nonzero(a <= 0) == 0


def test_hpm_structure_leaves_a_stochastic_sample_alone(mapped):
    V, F, img, r = mapped
    pat = r.report()["pattern"]
    assert not pat["periodic"] and pat["min_patch"] == 0.0
    off = hpm_texture(V, F, img, scale=3.0, seed=1, structure=False)
    assert off.uv.tobytes() == r.uv.tobytes() and np.array_equal(off.uv_faces, r.uv_faces)
    with pytest.raises(InputError, match="min_patch"):
        hpm_texture(V, F, img, scale=3.0, min_patch=-1.0)


def test_hpm_deterministic_and_pure(mapped):
    V, F, img, r = mapped
    V0, img0 = V.copy(), img.copy()
    again = hpm_texture(V, F, img, scale=3.0, seed=1)
    assert np.array_equal(V, V0) and np.array_equal(img, img0)
    assert again.uv.tobytes() == r.uv.tobytes()
    assert np.array_equal(again.uv_faces, r.uv_faces)
    other = hpm_texture(V, F, img, scale=3.0, seed=2)
    assert other.uv.shape != r.uv.shape or not np.array_equal(other.uv, r.uv)


def test_hpm_errors():
    V, F = icosphere(2)
    img = noise_image(32, 32)
    with pytest.raises(InputError, match="too small"):
        hpm_texture(V, F, img, scale=0.05)
    with pytest.raises(InputError, match="open"):
        Vg, Fg = grid_plane(4, 4)
        hpm_texture(Vg, Fg, img, scale=1.0)
    with pytest.raises(InputError, match="image"):
        hpm_texture(V, F, img[:, :, :2], scale=2.0)
    with pytest.raises(InputError, match="scale"):
        hpm_texture(V, F, img, scale=-1.0)


def test_hpm_textured_mesh_round_trip(mapped, tmp_path):
    V, F, img, r = mapped
    mesh = hpm_mesh(V, F, r, img, name="ball")
    for ext in ("glb", "obj"):
        out = tmp_path / f"ball.{ext}"
        write_mesh(out, mesh)
        back = read_mesh(out)
        assert back.texture is not None and back.texture.shape[:2] == img.shape[:2]
        assert back.has_uv
        # corner uv agree with the mapping (float32 in glTF)
        got = back.uv[back.uv_faces]
        assert np.allclose(np.sort(got.reshape(-1, 2), axis=0),
                           np.sort(r.uv[r.uv_faces].reshape(-1, 2), axis=0), atol=1e-5)


# ---------------------------------------------------------------------------
# CLI
# ---------------------------------------------------------------------------

@pytest.fixture()
def files(tmp_path):
    from PIL import Image
    V, F = icosphere(3)
    base = tmp_path / "ball.obj"
    write_mesh(base, Mesh(V, F))
    img = tmp_path / "noise.png"
    Image.fromarray(noise_image(64, 64)).save(img)
    return tmp_path, base, img


def test_cli_hpm_writes_glb_and_report(files, capsys):
    tmp, base, img = files
    out, rep = tmp / "out.glb", tmp / "r.json"
    assert main(["hpm", str(base), "--image", str(img), "--scale", "3", "-o", str(out),
                 "--report", str(rep)]) == 0
    mesh = read_mesh(out)
    assert mesh.has_uv and mesh.texture is not None
    data = json.loads(rep.read_text())
    assert [lv["level"] for lv in data["levels"]] == list(range(len(data["levels"])))
    assert {"placed", "subdivided", "mean_error"} <= set(data["levels"][0])


def test_cli_hpm_obj_writes_image_beside(files):
    tmp, base, img = files
    out = tmp / "out.obj"
    assert main(["hpm", str(base), "--image", str(img), "--scale", "3", "-o", str(out)]) == 0
    assert (tmp / "out.mtl").exists() and (tmp / "out.png").exists()


def test_cli_hpm_errors(files, capsys, monkeypatch):
    from PIL import Image
    tmp, base, img = files

    def err(args):
        code = main(["hpm", *args])
        line = capsys.readouterr().err.strip()
        assert code == 2 and line.count("\n") == 0 and line.startswith("geotex: error:")
        return line

    assert "too small" in err([str(base), "--image", str(img), "--scale", "0.01",
                               "-o", str(tmp / "a.glb")])
    assert "--scale" in err([str(base), "--image", str(img), "--scale", "-2",
                             "-o", str(tmp / "a.glb")])
    cmyk = tmp / "cmyk.jpg"
    Image.new("CMYK", (32, 32)).save(cmyk)
    assert "not 8-bit RGB or grey" in err([str(base), "--image", str(cmyk), "-o", str(tmp / "a.glb")])
    Vg, Fg = grid_plane(4, 4)
    open_base = tmp / "open.obj"
    write_mesh(open_base, Mesh(Vg, Fg))
    assert "open" in err([str(open_base), "--image", str(img), "-o", str(tmp / "a.glb")])
    fins = tmp / "fins.obj"
    Vf = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1]], float)
    Ff = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    write_mesh(fins, Mesh(Vf, Ff))
    assert "non-manifold" in err([str(fins), "--image", str(img), "-o", str(tmp / "a.glb")])
    assert ".glb or .obj" in err([str(base), "--image", str(img), "-o", str(tmp / "a.stl")])
    # coordinates the output cannot store are refused before any work (were refused
    # only when the finished texture was written)
    import geotex.image.hpm

    def no_work(*a, **k):
        raise AssertionError("hpm ran before refusing the coordinates")

    Vb, Fb = icosphere(1)
    huge = tmp / "huge.obj"
    write_mesh(huge, Mesh(Vb * 1e39, Fb))
    monkeypatch.setattr(geotex.image.hpm, "hpm_texture", no_work)
    assert "float32 range of glTF" in err([str(huge), "--image", str(img),
                                           "-o", str(tmp / "a.glb")])
    assert "1e+15 mm a relief" in err([str(huge), "--image", str(img), "--displace", "0.1",
                                       "-o", str(tmp / "a.stl")])
    monkeypatch.undo()
    assert "no such image" in err([str(base), "--image", str(tmp / "x.png"),
                                   "-o", str(tmp / "a.glb")])
    for bad in ("-5", "nan", "inf", "wide"):
        assert err([str(base), "--image", str(img), "--orientation-spread", bad,
                    "-o", str(tmp / "a.glb")]) == (
            f"geotex: error: --orientation-spread {bad}: give degrees >= 0 or 'any'")
    for bad in ("0", "-0.1", "nan", "1.5"):
        assert err([str(base), "--image", str(img), "--band", bad,
                    "-o", str(tmp / "a.glb")]).startswith(f"geotex: error: --band {float(bad)!r}")
    assert not (tmp / "a.glb").exists()


def test_cli_hpm_orientation_spread_any_searches_every_orientation(files, capsys):
    tmp, base, img = files
    out = tmp / "any.glb"
    assert main(["hpm", str(base), "--image", str(img), "--scale", "3",
                 "--orientation-spread", "any", "-o", str(out)]) == 0
    assert out.exists()


def test_hpm_follows_a_direction_field_and_cli_field(files, tmp_path):
    from geotex.fields.directions import smooth_direction_field
    from geotex.fields.store import save_direction_field
    V, F = icosphere(3)
    field = smooth_direction_field(V, F, symmetry=2, seed=0)
    img = noise_image(64, 64)
    r = hpm_texture(V, F, img, scale=3.0, seed=0, field=field)
    assert np.isfinite(r.uv).all() and r.report()["placements"] >= 1
    tmp, base, png = files
    fpath = tmp / "up.npz"
    save_direction_field(fpath, field)
    out = tmp / "f.glb"
    assert main(["hpm", str(base), "--image", str(png), "--scale", "3", "--field", str(fpath),
                 "-o", str(out)]) == 0
    assert read_mesh(out).has_uv


def test_topological_coordinates_and_edge_bands():
    from geotex.patches.flatten import edge_band
    V, F = icosphere(4)
    H = cluster_hierarchy(V, F)
    bh = barycentric_hierarchy(V, F, H)
    for li in (1, 2):
        lv = H[li]
        k = len(lv.controls(0))
        verts, M, faces = flatten_cluster(bh, li, 0, np.eye(k), topological=True)
        assert np.allclose(M.sum(axis=1), 1.0) and M.min() >= -1e-12
        # control vertices are their own corner
        ctrl = lv.controls(0)
        pos = np.searchsorted(verts, ctrl)
        assert np.allclose(M[pos], np.eye(k))
        # a band touches its edge and stays a strict part of the cluster
        loop = lv.boundary_loop(0)
        for e in range(k):
            band = edge_band(bh, li, 0, [e])
            assert 0 < band.size < faces.size
            a, b = ctrl[e], ctrl[(e + 1) % k]
            i, j = list(loop).index(a), list(loop).index(b)
            seg = loop[i:j + 1] if i <= j else np.concatenate([loop[i:], loop[:j + 1]])
            assert np.isin(seg, F[band]).mean() > 0.5
        wide = edge_band(bh, li, 0, [0], width=0.5)
        narrow = edge_band(bh, li, 0, [0])
        assert np.isin(narrow, wide).all() and wide.size > narrow.size


def test_hpm_topological_band_mode(mapped):
    V, F, img, _ = mapped
    r = hpm_texture(V, F, img, scale=3.0, seed=1, band_mode="topological")
    assert np.isfinite(r.uv).all() and r.report()["placements"] >= 2
    with pytest.raises(InputError, match="band_mode"):
        hpm_texture(V, F, img, scale=3.0, band_mode="rings")


def test_cli_hpm_relief_is_printable_and_refuses_a_textured_suffix(files, capsys):
    from geotex.check import check_mesh

    tmp, base, img = files
    out = tmp / "relief.stl"
    assert main(["hpm", str(base), "--image", str(img), "--scale", "3", "--displace", "0.05",
                 "--faces", "20000", "-o", str(out)]) == 0
    m = read_mesh(out)
    assert check_mesh(m.vertices, m.faces).printable
    r = np.linalg.norm(m.vertices, axis=1)
    assert r.max() > 1.0 + 0.02                           # raised somewhere
    capsys.readouterr()
    assert main(["hpm", str(base), "--image", str(img), "--displace", "0.05",
                 "-o", str(tmp / "x.glb")]) == 2
    assert "--displace" in capsys.readouterr().err and not (tmp / "x.glb").exists()


def test_cli_hpm_refines_a_base_too_coarse_for_the_default_scale(tmp_path, capsys):
    # a 12-triangle box: its faces are larger than the image at the default scale (a
    # quarter of the diagonal); the command refines it instead of refusing
    from PIL import Image

    from geotex.check import check_mesh

    V, F = box()
    base = tmp_path / "box.stl"
    write_mesh(base, Mesh(V, F))
    img = tmp_path / "noise.png"
    Image.fromarray(noise_image(64, 64)).save(img)
    out, rep = tmp_path / "box.glb", tmp_path / "box.json"
    assert main(["hpm", str(base), "--image", str(img), "-o", str(out), "--report", str(rep)]) == 0
    assert "refined by exact edge splits" in capsys.readouterr().out
    m = read_mesh(out)
    assert m.has_uv and np.isfinite(m.uv).all()
    doc = json.loads(rep.read_text())
    assert doc["input_faces"] == 12 and doc["faces"] > 12 and m.n_faces == doc["faces"]
    # the refined surface is the box's: every vertex on its boundary
    on_side = np.isclose(m.vertices, 0.0) | np.isclose(m.vertices, 1.0)
    assert on_side.any(axis=1).all()
    # the relief goes through the same refined mesh
    relief = tmp_path / "box.stl.out.stl"
    assert main(["hpm", str(base), "--image", str(img), "--displace", "0.02", "--faces",
                 "20000", "-o", str(relief)]) == 0
    r = read_mesh(relief)
    assert check_mesh(r.vertices, r.faces).printable


# ---------------------------------------------------------------------------
# face level and sub-pixel refinement
# ---------------------------------------------------------------------------

def test_refine_placement_recovers_a_subpixel_shift_and_angle():
    from geotex.image.hpm_fit import _refine_placement
    from geotex.image.hpm_kernels import _sample
    img = opponent_colors(noise_image(64, 64, seed=3).astype(np.float64) / 255.0)
    yy, xx = np.mgrid[0:14, 0:14]
    q = np.column_stack([xx.ravel() + 0.5, yy.ravel() + 0.5]) - 7.0
    a = np.radians(4.0)
    R_true = np.array([[np.cos(a), np.sin(a)], [-np.sin(a), np.cos(a)]])
    t_true = np.array([30.3, 27.6])
    target = _sample(img, q @ R_true.T + t_true)
    # start where the FFT would: the nearest whole pixel, the grid orientation 0
    R0, t0 = np.eye(2), np.round(t_true)
    e_start = float(np.sum((target - _sample(img, q @ R0.T + t0)) ** 2))
    R1, t1, e1 = _refine_placement(img, R0, t0, q, target, 2 * np.pi / 20)
    assert e1 < 0.1 * e_start
    assert np.linalg.norm(t1 - t_true) < 0.15
    assert abs(np.degrees(np.arctan2(R1[0, 1], R1[0, 0])) - 4.0) < 1.0
    # never worse than the start, even where the start is already the optimum
    R2, t2, e2 = _refine_placement(img, R_true, t_true, q, target, 2 * np.pi / 20)
    assert e2 <= 1e-12 and np.allclose(t2, t_true) and np.allclose(R2, R_true)


def test_compiled_sampling_equals_the_numpy_path_bit_for_bit():
    from geotex.image.hpm_kernels import _sample
    rng = np.random.default_rng(4)
    img = opponent_colors(noise_image(37, 53, seed=5).astype(np.float64) / 255.0)
    xy = np.vstack([rng.uniform(-5.0, 60.0, (5000, 2)),           # inside and clamped
                    np.mgrid[0:54:0.5, 0:38:0.5].reshape(2, -1).T,  # pixel centres, edges
                    [[0.5, 0.5], [53.5, 37.5], [-0.0, 0.0]]])
    slow, fast = _sample(img, xy), _sample(img, xy, True)
    assert fast.dtype == slow.dtype and fast.shape == slow.shape
    assert np.array_equal(fast, slow)
    # NaN positions keep the numpy path (whose float-to-index cast of a NaN fails)
    bad = xy[:3].copy()
    bad[1, 0] = np.nan
    with np.errstate(invalid="ignore"), pytest.raises(IndexError):
        _sample(img, bad, True)


@pytest.mark.parametrize("image", ["noise", "stripes"])
def test_hpm_compiled_sampling_gives_the_same_uv(monkeypatch, image):
    # compiled sampling, rasterization, energies, band search and relaxation error
    # against the numpy / scipy paths; stripes: the automatic field at the face level
    # and the lattice moves
    import geotex.image.hpm as hpm
    V, F = torus(1.0, 0.4, n_major=32, n_minor=12)
    img = noise_image(64, 64) if image == "noise" else stripe_image()
    kw = dict(scale=0.6, seed=1, max_error=0.2)
    monkeypatch.setattr(hpm, "SAMPLE_JIT_FACES", 10 ** 9)
    monkeypatch.setattr(hpm, "JIT_MIN_SIZE", 10 ** 9)
    slow = hpm_texture(V, F, img, **kw)
    monkeypatch.setattr(hpm, "SAMPLE_JIT_FACES", 0)
    fast = hpm_texture(V, F, img, **kw)
    assert np.array_equal(slow.uv, fast.uv) and np.array_equal(slow.uv_faces, fast.uv_faces)
    assert slow.report() == fast.report()
    if image == "stripes":
        levels = fast.report()["levels"]
        assert fast.report()["pattern"]["field"] == "auto"
        assert levels[-1]["matched_faces"] > 0


@pytest.fixture(scope="module")
def face_level_runs():
    # the torus of test_hpm_fills_few_faces_at_face_level, where some finest
    # clusters are refused and their faces reach the face level
    V, F = torus(1.0, 0.4, n_major=48, n_minor=16)
    img = noise_image(64, 64)
    kw = dict(scale=0.6, seed=2, max_error=0.2)
    return V, F, {fm: hpm_texture(V, F, img, face_match=fm, **kw) for fm in (True, False)}


def test_hpm_face_level_matches_remaining_faces(face_level_runs):
    V, F, runs = face_level_runs
    on, off = runs[True], runs[False]
    lv_on, lv_off = on.report()["levels"][-1], off.report()["levels"][-1]
    # the same faces reach the face level (the cluster levels do not depend on it)
    reached = lv_off["filled_faces"]
    assert reached > 20 and lv_off["matched_faces"] == 0 and lv_off["placed"] == 0
    assert lv_on["matched_faces"] + lv_on["filled_faces"] == reached
    assert lv_on["matched_faces"] > lv_on["filled_faces"] and lv_on["placed"] > 0
    # matched faces are placements of the face level; unfolded ones have none
    L = len(on.levels)
    matched = (on.face_level == L - 1) & (on.patch >= 0)
    assert np.count_nonzero(matched) == lv_on["matched_faces"]
    assert np.count_nonzero(on.patch < 0) == lv_on["filled_faces"]
    assert lv_on["mean_error"] is not None and 0 <= lv_on["mean_error"] <= 0.2
    # every face textured, no face reversed in texture space
    t = on.uv[on.uv_faces]
    d = (t[:, 1, 0] - t[:, 0, 0]) * (t[:, 2, 1] - t[:, 0, 1]) \
        - (t[:, 1, 1] - t[:, 0, 1]) * (t[:, 2, 0] - t[:, 0, 0])
    assert np.isfinite(on.uv).all() and (d > 0).all()


def test_hpm_face_group_and_subpixel_options_are_checked():
    V, F = icosphere(2)
    img = noise_image(32, 32)
    with pytest.raises(InputError, match="face_group"):
        hpm_texture(V, F, img, scale=3.0, face_group=0)
    a = hpm_texture(V, F, img, scale=3.0, seed=4, subpixel=True)
    b = hpm_texture(V, F, img, scale=3.0, seed=4, subpixel=True)
    assert np.array_equal(a.uv, b.uv) and np.array_equal(a.uv_faces, b.uv_faces)


def test_cli_hpm_face_level_and_subpixel_flags(files):
    tmp, base, img = files
    reps = {}
    for flags in (["--face-level", "unfold"], ["--subpixel"]):
        out, rep = tmp / "fl.glb", tmp / "fl.json"
        assert main(["hpm", str(base), "--image", str(img), "--scale", "0.8", "--max-error",
                     "0.15", "-o", str(out), "--report", str(rep)] + flags) == 0
        reps[flags[0]] = json.loads(rep.read_text())["levels"][-1]
    assert reps["--face-level"]["matched_faces"] == 0
    assert reps["--face-level"]["filled_faces"] > 0
    assert reps["--subpixel"]["matched_faces"] > 0


def test_cli_hpm_structure_flags(tmp_path, capsys):
    from PIL import Image
    V, F = torus(1.0, 0.4, n_major=48, n_minor=16)
    base = tmp_path / "torus.obj"
    write_mesh(base, Mesh(V, F))
    img = tmp_path / "stripes.png"
    Image.fromarray(stripe_image()).save(img)
    reps = {}
    for flags in ([], ["--structure", "off"], ["--min-patch", "0"], ["--min-patch", "2"]):
        out, rep = tmp_path / "s.glb", tmp_path / "s.json"
        assert main(["hpm", str(base), "--image", str(img), "--scale", "2", "-o", str(out),
                     "--report", str(rep)] + flags) == 0
        reps[" ".join(flags)] = json.loads(rep.read_text())
    out = capsys.readouterr().out
    assert "periodic image, 8 px period" in out and "patches span a median" in out
    span = reps[""]["pattern"]["patch_periods"]
    assert np.isfinite(span) and span > 0
    # larger patches span more periods: the paper's minimal patch size, --min-patch 2
    assert reps["--min-patch 2"]["pattern"]["patch_periods"] > span
    assert reps["--structure off"]["pattern"].get("patch_periods") is None
    forced = {k: sum(lv["forced"] for lv in r["levels"]) for k, r in reps.items()}
    assert forced["--min-patch 2"] > forced[""] >= 0
    assert forced["--structure off"] == 0 and forced["--min-patch 0"] == 0
    assert reps["--structure off"]["pattern"]["min_patch"] == 0.0
    assert reps[""]["pattern"]["band_width"] > reps["--structure off"]["pattern"]["band_width"]
    assert main(["hpm", str(base), "--image", str(img), "--scale", "2", "--min-patch", "-1",
                 "-o", str(tmp_path / "x.glb")]) != 0
    assert "--min-patch" in capsys.readouterr().err


# ---------------------------------------------------------------------------
# one orientation over the surface: a smooth direction field (issue 16, paper Fig. 10)
# ---------------------------------------------------------------------------

def field_deviation(V, F, r, img, vectors, sym):
    """Per face: angle (degrees) between the image x axis on the surface and the field."""
    uv = r.uv[r.uv_faces] * [img.shape[1], img.shape[0]]
    P = V[F]
    E = np.stack([P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]], 2)
    D = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], 2)
    X = (E @ np.linalg.inv(D))[:, :, 0]
    n = np.cross(E[:, :, 0], E[:, :, 1])
    c = np.sum(X * vectors, 1)
    s = np.sum(np.cross(vectors, X) * n, 1) / np.linalg.norm(n, axis=1)
    return np.degrees(np.abs(np.angle(np.exp(1j * sym * np.arctan2(s, c))))) / sym


def test_quarter_turn_symmetry_tells_a_grid_from_stripes():
    from geotex.image.fftmatch import quarter_turn_symmetry
    assert quarter_turn_symmetry(checker_image(8, 96)) > 0.9
    assert quarter_turn_symmetry(stripe_image()) < 0.3
    assert quarter_turn_symmetry(np.full((32, 32, 3), 7, np.uint8)) == 0.0
    with pytest.raises(InputError):
        quarter_turn_symmetry(np.zeros((4, 4)))


def test_pattern_field_symmetry_and_turn():
    from geotex.image.hpm_pattern import _pattern_field
    V, F = icosphere(3)
    v2, s2 = _pattern_field(V, F, stripe_image(), None)
    v4, s4 = _pattern_field(V, F, checker_image(8, 96), None)
    assert (s2, s4) == (2, 4)
    t, _ = _pattern_field(V, F, stripe_image(), 30.0)
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    ang = np.degrees(np.arctan2(np.sum(np.cross(v2, t) * n, 1), np.sum(v2 * t, 1)))
    assert np.allclose(ang, 30.0, atol=1e-6)
    assert np.allclose(np.sum(t * n, 1), 0.0, atol=1e-9)


def test_hpm_field_keeps_one_orientation_on_a_torus():
    # stripes on a torus: the neighbours' orientation drifts from patch to patch and
    # separately grown regions meet turned; with the smooth line field (no singularity
    # on a torus) every patch follows it and the stripes turn little across borders
    from geotex.image.hpm_pattern import _pattern_field
    V, F = torus(1.0, 0.4, n_major=96, n_minor=26)
    img = stripe_image()
    on = hpm_texture(V, F, img, scale=2.0, seed=1)
    off = hpm_texture(V, F, img, scale=2.0, seed=1, orientation_field="never")
    vec, sym = _pattern_field(V, F, img, None)
    assert sym == 2
    dev_on = field_deviation(V, F, on, img, vec, sym)
    r_on, r_off = border_rotation(V, F, on), border_rotation(V, F, off)
    m_on = np.minimum(r_on % 180, 180 - r_on % 180)
    m_off = np.minimum(r_off % 180, 180 - r_off % 180)
    # measured (seed 1): deviation from the field median / p75 / p95 1.9 / 4.5 / 16.8
    # degrees; rotation across borders (mod 180) p75 / p90 7.4 / 14.0 with the field,
    # 21.3 / 50.2 without; pattern turned by 180 degrees across 0.5 % of the borders
    assert np.quantile(dev_on, 0.75) < 8.0 and np.quantile(dev_on, 0.95) < 25.0
    assert np.quantile(m_on, 0.75) < 0.5 * np.quantile(m_off, 0.75)
    assert np.quantile(m_on, 0.9) < 0.5 * np.quantile(m_off, 0.9)
    assert np.quantile(m_on, 0.75) < 10.0
    assert np.mean(r_on > 150.0) < 0.02
    assert on.report()["pattern"]["field_symmetry"] == 2
    assert "field_symmetry" not in off.report()["pattern"]


def test_hpm_orientation_field_options_and_stochastic_samples(files, capsys):
    V, F = icosphere(3)
    img = noise_image(64, 64)            # stochastic: no field unless asked for
    auto = hpm_texture(V, F, img, scale=3.0, seed=0)
    never = hpm_texture(V, F, img, scale=3.0, seed=0, orientation_field="never")
    assert np.array_equal(auto.uv, never.uv) and np.array_equal(auto.uv_faces, never.uv_faces)
    assert "field" not in auto.report()["pattern"]
    always = hpm_texture(V, F, img, scale=3.0, seed=0, orientation_field="always")
    assert always.report()["pattern"]["field"] == "auto"
    assert np.isfinite(always.uv).all()
    again = hpm_texture(V, F, img, scale=3.0, seed=0, orientation_field="always")
    assert np.array_equal(always.uv, again.uv)
    with pytest.raises(InputError, match="orientation_field"):
        hpm_texture(V, F, img, scale=3.0, orientation_field="yes")
    with pytest.raises(InputError, match="field_tolerance"):
        hpm_texture(V, F, img, scale=3.0, field_tolerance=-1.0)
    tmp, base, png = files
    rep = tmp / "o.json"
    assert main(["hpm", str(base), "--image", str(png), "--scale", "3", "--orientation",
                 "field", "--report", str(rep), "-o", str(tmp / "o.glb")]) == 0
    assert json.loads(rep.read_text())["pattern"]["field"] == "auto"
    assert main(["hpm", str(base), "--image", str(png), "--scale", "3", "--field-tolerance",
                 "-2", "-o", str(tmp / "x.glb")]) != 0
    assert "--field-tolerance" in capsys.readouterr().err


def test_hpm_user_field_is_followed_and_continued():
    # a user's line field: every patch takes its direction (before: +-20 degrees of it,
    # no neighbour continuation), the neighbours' continuations are kept when near it
    from geotex.fields.directions import smooth_direction_field
    from geotex.fields.combing import comb_direction_field
    V, F = torus(1.0, 0.4, n_major=64, n_minor=20)
    fld = smooth_direction_field(V, F, symmetry=2, seed=0)
    img = stripe_image()
    r = hpm_texture(V, F, img, scale=2.0, seed=0, field=fld)
    assert r.report()["pattern"]["field"] == "given"
    assert sum(lv["continued"] for lv in r.report()["levels"]) > 0
    # face level: continuations under the threshold are taken without the FFT search
    last = r.report()["levels"][-1]
    assert 0 < last["quick"] <= last["continued"]
    assert max(r.levels[-1].errors) <= 0.35
    dev = field_deviation(V, F, r, img, comb_direction_field(V, F, fld).vectors, 2)
    assert np.quantile(dev, 0.75) < 8.0


def test_hpm_automatic_field_on_a_mesh_with_zero_area_faces():
    # simplified meshes have faces of zero area (Spot at 30k: 81), on which no field is
    # defined: the field is solved without them and they take a neighbour's vector
    from geotex.image.hpm_pattern import _pattern_field
    V, F = torus(1.0, 0.4, n_major=48, n_minor=16)
    V = V.copy()
    V[F[0, 2]] = 0.5 * (V[F[0, 0]] + V[F[0, 1]])     # face 0 collapses onto its edge
    from geotex.mesh.geometry import degenerate_faces
    bad = degenerate_faces(V, F)
    assert bad.size >= 1
    vec, sym = _pattern_field(V, F, stripe_image(), None)
    assert np.allclose(np.linalg.norm(vec, axis=1), 1.0)
    r = hpm_texture(V, F, stripe_image(), scale=2.0, seed=0)
    assert r.report()["pattern"]["field"] == "auto" and np.isfinite(r.uv).all()
