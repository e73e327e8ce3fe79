"""Mesh quilting: min-cut, ICP, Laplacian editing, element merging, the quilting loop."""

from __future__ import annotations

import itertools

import igl
import numpy as np
import pytest
from scipy.sparse import csr_matrix as sp_csr

from geotex.check.report import check_mesh
from geotex.errors import InputError
from geotex.mesh.geometry import signed_volume
from geotex.mesh.primitives import box, icosphere
from geotex.mesh.solid import arrays_of_manifold, manifold_of
from geotex.quilting import (closed_element_ok, icp_translation, laplacian_deformed,
                             merge_elements, min_cut, min_cut_keep, quilt_texture)
from geotex.quilting.elements import capped
from geotex.testing import assert_printable


# ----------------------------------------------------------------------------
# test textures (self-contained generators)

def stud(center, r=0.16, height=0.15, depth=0.05, sub=2):
    """A closed dome standing on z = 0 with a flat bottom at z = -depth."""
    V, F = icosphere(sub)
    V = V * [r, r, 1.0]
    V[:, 2] = np.where(V[:, 2] > 0, V[:, 2] * height, np.maximum(V[:, 2] * depth * 2, -depth))
    return V + [center[0], center[1], 0.0], F


def strand(center, length=0.8, r=0.07, depth=0.03, sub=2):
    """A long capped strand along x (a stretched dome), standing on z = 0."""
    V, F = stud((0, 0), r=1.0, height=1.0, depth=depth / r, sub=sub)
    V = V * [length / 2, r, r]
    return V + [center[0], center[1], 0.0], F


def texture(kind="studs", size=(1.5, 1.5), pitch=0.5, seed=0, sub=2):
    rng = np.random.default_rng(seed)
    parts = []
    nx, ny = int(round(size[0] / pitch)), int(round(size[1] / pitch))
    for i, j in itertools.product(range(nx), range(ny)):
        c = ((i + 0.5) * pitch, (j + 0.5) * pitch) + rng.uniform(-0.04, 0.04, 2)
        if kind == "studs":
            parts.append(stud(c, r=0.16 * rng.uniform(0.85, 1.1), sub=sub))
        else:
            parts.append(strand(c, length=pitch * 0.9, sub=sub))
    V = np.concatenate([p[0] for p in parts])
    offs = np.cumsum([0] + [len(p[0]) for p in parts])
    F = np.concatenate([p[1] + o for p, o in zip(parts, offs)])
    return V, F


class FakeExemplar:
    """An exemplar-like object (the duck type quilt_texture accepts)."""

    def __init__(self, V, F, size):
        self.vertices, self.faces, self.size = V, F, size


# ----------------------------------------------------------------------------
# min-cut

def test_min_cut_path_and_value():
    edges = np.array([[0, 1], [1, 2], [2, 3], [3, 4]])
    keep = min_cut_keep(5, edges, [4.0, 3.0, 0.5, 2.0], source=[0], sink=[4])
    assert keep.tolist() == [True, True, True, False, False]
    cut = min_cut(5, edges, [4.0, 3.0, 0.5, 2.0], source=[0], sink=[4])
    assert cut.value == 0.5


def test_min_cut_matches_brute_force():
    rng = np.random.default_rng(3)
    n = 9
    edges = np.array([(i, j) for i in range(n) for j in range(i + 1, n) if rng.random() < 0.5])
    w = rng.uniform(0.1, 5.0, len(edges))
    best = np.inf
    for bits in itertools.product([0, 1], repeat=n - 2):
        side = np.array([1, *bits, 0], dtype=bool)  # node 0 source, node n-1 sink
        best = min(best, w[side[edges[:, 0]] != side[edges[:, 1]]].sum())
    cut = min_cut(n, edges, w, source=[0], sink=[n - 1])
    assert cut.keep[0] and not cut.keep[-1]
    # integer scaling may pick a cut within rounding of the optimum
    assert cut.value == pytest.approx(best, rel=1e-6)


def test_min_cut_terminal_sets_and_masks():
    # two triangles joined by one weak edge; the heavy sides are tied to the terminals
    edges = np.array([[0, 1], [1, 2], [0, 2], [2, 3], [3, 4], [4, 5], [3, 5]])
    w = np.array([9, 9, 9, 1, 9, 9, 9], float)
    src = np.zeros(6, bool)
    src[[0, 1]] = True
    keep = min_cut_keep(6, edges, w, source=src, sink=[4, 5])
    assert keep.tolist() == [True, True, True, False, False, False]


def test_min_cut_errors():
    edges = np.array([[0, 1]])
    with pytest.raises(InputError, match="both the source and the sink"):
        min_cut_keep(2, edges, [1.0], source=[0], sink=[0, 1])
    with pytest.raises(InputError, match="non-negative"):
        min_cut_keep(2, edges, [-1.0], source=[0], sink=[1])
    with pytest.raises(InputError, match="one value per edge"):
        min_cut_keep(2, edges, [1.0, 2.0], source=[0], sink=[1])
    with pytest.raises(InputError, match="at least one node"):
        min_cut_keep(2, edges, [1.0], source=[], sink=[1])


# ----------------------------------------------------------------------------
# ICP

def test_icp_recovers_translation_and_stops_when_converged():
    V, F = icosphere(3)
    shift = np.array([0.08, -0.05, 0.03])
    t, info = icp_translation(V[::5] - shift, V, F, max_iterations=200, tol=1e-10)
    assert np.abs(t - shift).max() < 1e-6
    assert info.converged and info.iterations < 200
    assert info.rms < 1e-6


def test_icp_point_to_plane_converges_fast():
    V, F = icosphere(3)
    shift = np.array([0.08, -0.05, 0.03])
    t, info = icp_translation(V[::5] - shift, V, F, method="plane", tol=1e-12)
    assert np.abs(t - shift).max() < 1e-9 and info.converged and info.iterations < 20
    with pytest.raises(InputError, match="method"):
        icp_translation(V, V, F, method="normal")


def test_icp_iteration_cap_and_fixed_axis():
    V, F = icosphere(3)
    t, info = icp_translation(V[::5] - [0.2, 0, 0.1], V, F, max_iterations=2, tol=0.0)
    assert info.iterations == 2 and not info.converged
    t, _ = icp_translation(V[::5] - [0.1, 0.05, 0.1], V, F, free=(True, True, False),
                           t0=(0, 0, 0.25))
    assert t[2] == 0.25
    with pytest.raises(InputError, match="t0"):
        icp_translation(V, V, F, t0=(0, 0))
    with pytest.raises(InputError, match="points"):
        icp_translation(np.zeros((0, 3)), V, F)


# ----------------------------------------------------------------------------
# Laplacian editing

def test_laplacian_fixed_bit_exact_and_targets_reached():
    V, F = icosphere(3)
    top = np.flatnonzero(V[:, 2] > 0.9)
    fixed = np.flatnonzero(V[:, 2] < -0.3)
    goal = V[top] + [0, 0, 0.3]
    W = laplacian_deformed(V, F, (top, goal), mu=100.0, fixed=fixed)
    assert np.array_equal(W[fixed], V[fixed])          # bit-exact
    before = np.linalg.norm(V[top] - goal, axis=1).mean()
    after = np.linalg.norm(W[top] - goal, axis=1).mean()
    assert after < 0.2 * before
    weak = laplacian_deformed(V, F, (top, goal), mu=0.01, fixed=fixed)
    assert np.linalg.norm(weak[top] - goal, axis=1).mean() > after
    assert not np.shares_memory(W, V)


def test_laplacian_identity():
    V, F = icosphere(2)
    assert np.array_equal(laplacian_deformed(V, F), V)
    W = laplacian_deformed(V, F, (np.arange(0, len(V), 7), V[::7]), fixed=[1, 2])
    assert np.abs(W - V).max() < 1e-9
    Wu = laplacian_deformed(V, F, (np.arange(0, len(V), 7), V[::7]), laplacian="uniform")
    assert np.abs(Wu - V).max() < 1e-9


def test_laplacian_preserves_laplacian_coordinates_where_unconstrained():
    V, F = icosphere(3)
    L = sp_csr(igl.cotmatrix(V, F))
    # targets that only translate: the Laplacian coordinates are kept exactly and
    # every vertex follows the translation (to within the tiny regularisation
    # towards the rest positions: measured 8e-5 of a 0.37 shift)
    top = np.flatnonzero(V[:, 2] > 0.8)
    shift = np.array([0.2, -0.1, 0.3])
    W = laplacian_deformed(V, F, (top, V[top] + shift), mu=100.0)
    np.testing.assert_allclose(W - V, np.broadcast_to(shift, V.shape), atol=1e-3)
    delta = L @ V
    assert np.abs(L @ W - delta).max() < 1e-3 * np.abs(delta).max()     # measured 1.5e-4
    # a real edit (lift the top, hold the bottom): the result is the least-squares
    # optimum of sum |L w - L v|^2 + mu sum |w_c - p_c|^2 over the free vertices
    fixed = np.flatnonzero(V[:, 2] < -0.5)
    goal = V[top] + [0.0, 0.0, 0.4]
    mu = 10.0
    W = laplacian_deformed(V, F, (top, goal), mu=mu, fixed=fixed)
    free = np.setdiff1d(np.arange(len(V)), fixed)
    scale = float(abs(L.diagonal()).mean()) ** 2
    grad = L.T @ (L @ W - L @ V)
    grad[top] += mu * scale * (W[top] - goal)
    grad += 1e-8 * scale * (W - V)                       # the documented regularisation
    assert np.abs(grad[free]).max() < 1e-8 * np.abs(L.T @ (L @ V)).max()
    assert np.array_equal(W[fixed], V[fixed])
    # so it changes the Laplacian coordinates less than a plain stretch that meets
    # the same constraints (a linear ramp of the lift from the held to the lifted part)
    ramp = V.copy()
    ramp[:, 2] += 0.4 * np.clip((V[:, 2] + 0.5) / 1.3, 0.0, 1.0)
    def objective(X):
        return (np.sum((L @ X - L @ V) ** 2)
                + mu * scale * np.sum((X[top] - goal) ** 2))
    assert objective(W) < 0.8 * objective(ramp)               # measured 0.70


def test_laplacian_errors():
    V, F = icosphere(1)
    with pytest.raises(InputError, match="mu"):
        laplacian_deformed(V, F, ([0], [V[0]]), mu=0)
    with pytest.raises(InputError, match="targets"):
        laplacian_deformed(V, F, ([0, 1], [V[0]]))
    with pytest.raises(InputError, match="laplacian"):
        laplacian_deformed(V, F, ([0], [V[0]]), laplacian="mean")


# ----------------------------------------------------------------------------
# merging

def _union_volume(VA, FA, VB, FB):
    return signed_volume(*arrays_of_manifold(manifold_of(VA, FA) + manifold_of(VB, FB)))


@pytest.mark.parametrize("offset", [(0.15, 0.05), (0.22, 0.1)])
def test_merge_two_studs_stitches_one_closed_element(offset):
    VA, FA = stud((0, 0))
    VB, FB = stud(offset, r=0.14)
    r = merge_elements(VA, FA, VB, FB, align=False)
    assert r.status == "stitched", r.reason
    assert closed_element_ok(r.vertices, r.faces) == ""
    assert_printable(r.vertices, r.faces)
    # the stitched element encloses (nearly) the union of the two
    assert signed_volume(r.vertices, r.faces) == pytest.approx(
        _union_volume(VA, FA, VB, FB), rel=0.05)
    assert 0 < r.seam_gap < 0.1 and np.isfinite(r.seam_normal_jump)


def test_merge_keeps_fixed_vertices_and_separates_far_elements():
    VA, FA = stud((0, 0))
    VB, FB = stud((0.12, 0.0))
    fixed = VA[:, 0] < -0.1
    r = merge_elements(VA, FA, VB, FB, fixed_a=fixed)
    assert r.status in ("stitched", "union", "absorbed")
    assert closed_element_ok(r.vertices, r.faces) == ""
    got = {tuple(p) for p in r.vertices[r.fixed]}
    assert got == {tuple(p) for p in VA[fixed]}
    far = merge_elements(VA, FA, *stud((1.0, 0.0)))
    assert far.status == "separate" and far.faces.shape[0] == 2 * FA.shape[0]


@pytest.mark.parametrize("center", [(0.16, 0.3), (0.25, 0.45), (0.45, 0.3)])
def test_merge_never_leaves_the_domain(center):
    VA, FA = stud((0.3, 0.2))               # inside the domain x >= 0.1
    VB, FB = stud(center, r=0.14)
    r = merge_elements(VA, FA, VB, FB, domain=(0.1, 0.0, 1.0, 1.0), align=False)
    assert closed_element_ok(r.vertices, r.faces) == ""
    assert (r.vertices[:, 0] >= 0.1).all()
    if VB[:, 0].min() < 0.1:                # B crosses the domain edge
        assert r.status in ("dropped", "stitched")
        if r.status == "dropped":
            assert np.array_equal(r.vertices, VA)
    else:
        assert r.status == "stitched", r.reason


def test_matching_energy_counts_only_covered_vertices_and_finds_the_weave_phase():
    from geotex.exemplars import exemplar
    from geotex.quilting import ExemplarIndex, matching_energy
    ex = exemplar("weave", size=(2.0, 2.0), seed=0)
    V, F = ex.vertices, ex.faces
    N = igl.per_vertex_normals(V, F)
    index = ExemplarIndex(V, F)
    # the texture is the exemplar itself; a copy shifted by an odd number of
    # pitches along one axis swaps over and under, a diagonal or even shift does not
    good = [(1.0, 0.0, 0.0), (0.0, -1.0, 0.0), (0.5, 0.5, 0.0), (-0.5, 0.5, 0.0)]
    bad = [(0.5, 0.0, 0.0), (0.0, 0.5, 0.0), (-1.5, 0.0, 0.0)]
    E = matching_energy(V, N, index, good + bad, lam=2.0, footprint=ex.size)
    assert E[:len(good)].max() + 0.2 < E[len(good):].min()      # measured 1.33 vs 1.64
    # counting every vertex instead rewards copies that stay over the texture
    E_all = matching_energy(V, N, index, [(0.5, 0.0, 0.0), (1.0, 0.0, 0.0)], lam=2.0)
    assert E_all[0] < E_all[1]
    # a copy that covers no vertex cannot be scored
    assert np.isinf(matching_energy(V, N, index, [(5.0, 5.0, 0.0)], lam=2.0,
                                    footprint=ex.size)[0])


def _weave_strand(k=0):
    from geotex.exemplars import exemplar
    from geotex.quilting import split_elements
    ex = exemplar("weave", size=(2.0, 2.0), seed=0)
    e = split_elements(ex.vertices, ex.faces, element_ids=ex.elements())[k]
    return e.V, e.F


@pytest.mark.parametrize("k, shift", [(0, (1.0, 0.0)), (0, (-1.0, 0.0)), (4, (0.0, 1.0))])
def test_merge_two_pieces_of_a_strand_into_one_longer_strand(k, shift):
    VB, FB = _weave_strand(k)
    VA = VB + [shift[0], shift[1], 0.0]
    r = merge_elements(VA, FB, VB, FB, corresponding_only=True)
    assert r.status == "stitched", r.reason
    assert closed_element_ok(r.vertices, r.faces) == ""
    assert_printable(r.vertices, r.faces)
    axis = 0 if k < 4 else 1
    assert np.ptp(r.vertices[:, axis]) == pytest.approx(3.0, abs=0.05)   # 2 + 2 - overlap 1
    # one and a half strands of material (measured +0.7 % .. +0.9 %: the caps)
    assert signed_volume(r.vertices, r.faces) == pytest.approx(
        1.5 * signed_volume(VB, FB), rel=0.02)
    # the cut loops are welded into one seam (no strip, no gap) and the seam
    # bends the strand far less than its own rings do (mean 10.8 degrees across
    # a ring of the exemplar strand): measured mean 1.3 .. 1.8, max 1.4 .. 2.0
    # (before B was cut on A's seam and A where the surfaces face the same
    # way: mean 1.8 .. 3.5, max 1.9 .. 3.7)
    assert r.seam_gap == 0.0 and r.corresponding and r.seam_edges >= 12
    assert r.seam_normal_jump_mean < 2.5 and r.seam_normal_jump < 3.0
    # without the weld the loops, now on one ring, are joined by a strip with a
    # tiny gap, or (shift (1, 0): the strip self-intersects) the pair is united
    s = merge_elements(VA, FB, VB, FB, corresponding_only=True, weld=False)
    assert (s.status == "stitched" and s.seam_gap > 0) or s.status == "union"
    assert closed_element_ok(s.vertices, s.faces, intersections=False) == ""


def test_zip_loops_welds_two_loops_into_one_seam():
    from geotex.quilting.seam import boundary_loops, zip_loops
    # two open cylinders meeting end to end: 8 and 6 vertices around
    def tube(n, z0, z1, phase):
        t = 2 * np.pi * (np.arange(n) + phase) / n
        ring = np.c_[np.cos(t), np.sin(t)]
        V = np.r_[np.c_[ring, np.full(n, z0)], np.c_[ring, np.full(n, z1)]]
        i = np.arange(n)
        j = (i + 1) % n
        F = np.r_[np.c_[i, j, j + n], np.c_[i, j + n, i + n]]
        return V, F
    V1, F1 = tube(8, 0.0, 1.0, 0.0)
    V2, F2 = tube(6, 1.0, 2.0, 0.25)
    V = np.r_[V1, V2]
    F = np.r_[F1, F2 + 16]
    la = [l for l in boundary_loops(F1, 16) if V1[l[0], 2] == 1.0][0]
    lb = [l for l in boundary_loops(F2, 12) if V2[l[0], 2] == 1.0][0] + 16
    out = zip_loops(F, la, V[la], lb, V[lb])
    assert out is not None
    Fz, parent, rep = out
    assert rep == {} and Fz.shape[0] == F.shape[0] + 8 + 6
    assert np.array_equal(np.bincount(parent, minlength=len(F)) >= 1, np.ones(len(F), bool))
    # the two tube ends now share one seam: only the two far rims stay open
    loops = boundary_loops(Fz, len(V))
    assert sorted(len(l) for l in loops) == [6, 8]
    assert {float(V[l[0], 2]) for l in loops} == {0.0, 2.0}
    # equal rings in phase weld vertex to vertex
    V3, F3 = tube(8, 1.0, 2.0, 0.0)
    V = np.r_[V1, V3]
    F = np.r_[F1, F3 + 16]
    lb = [l for l in boundary_loops(F3, 16) if V3[l[0], 2] == 1.0][0] + 16
    Fz, parent, rep = zip_loops(F, la, V[la], lb, V[lb], weld=0.5)
    assert len(rep) == 8 and Fz.shape[0] == F.shape[0]
    assert not np.isin(Fz, list(rep)).any()


def test_matched_on_loops_keeps_the_order_of_offset_flat_cross_sections():
    from geotex.quilting.seam import closest_on_polyline, matched_on_loops
    # a flat strand's cross-section (12 vertices, 5:1) and a copy offset
    # sideways and up (two strand pieces whose loops were cut half a ring
    # apart), running the other way from another start, as the boundary
    # loops of two pieces do
    t = 2 * np.pi * np.arange(12) / 12
    Pa = np.c_[0.18 * np.cos(t), np.zeros(12), 0.035 * np.sin(t)]
    off = np.array([-0.014, -0.028, 0.008])
    Pb = np.roll((Pa + off)[::-1], 5, axis=0)
    Qa, Qb = matched_on_loops(Pa, Pb)
    # congruent loops: every vertex corresponds to its own copy (to 1e-4:
    # the offset search samples 8 points per vertex, refined by a parabola)
    np.testing.assert_allclose(Qa - Pa, np.tile(off, (12, 1)), atol=1e-4)
    np.testing.assert_allclose(Pb - Qb, np.tile(off, (12, 1)), atol=1e-4)
    # the closest point does not: at the pointed ends it slides along the
    # other loop (what folded a weld of the 4x3 weave quilt, seed 3)
    assert np.abs(closest_on_polyline(Pa, Pb) - Pa - off).max() > 0.005
    # loops of different vertex counts: the corresponding points lie on the
    # other loop and go round it in the same order (angle about its centre)
    Pc = np.c_[0.18 * np.cos(-t[:9] * 12 / 9), np.zeros(9), 0.035 * np.sin(-t[:9] * 12 / 9)]
    Qa, Qc = matched_on_loops(Pa, Pc)
    assert np.abs(closest_on_polyline(Qa, Pc) - Qa).max() < 1e-12
    turn = np.unwrap(np.arctan2(Qa[:, 2] / 0.035, Qa[:, 0] / 0.18))
    assert (np.diff(turn) > 0).all()
    assert matched_on_loops(Pa[:2], Pc) is None


def test_quilted_weave_welds_where_strand_loops_lie_half_a_ring_apart():
    from geotex.exemplars import exemplar
    # 2x1.5 -> 4x3, seed 3: one join's loops lie half a ring apart, offset
    # sideways (before: the weld folded, the strip bridged 0.29 edge lengths
    # with a 32 degree bend), and the cut of another join ran on a ring where
    # the strand creases by 23 degrees (before the crease cost)
    ex = exemplar("weave", size=(2.0, 1.5), seed=0)
    r = quilt_texture(ex, out_size=(4.0, 3.0), seed=3, boundary="clip")
    rep = r.report
    assert rep.valid and rep.merges["stitched"] >= 12, rep.summary()
    # measured: 15 of 15 welded, seam jumps 2.0 mean of maxima, 2.9 largest
    assert rep.seam_gap_max == 0.0
    assert rep.seam_normal_jump_mean < 3.0 and rep.seam_normal_jump_max < 5.0


def test_quilted_weave_joins_strands_and_prints_on_a_slab():
    from geotex.exemplars import exemplar
    ex = exemplar("weave", size=(2.0, 2.0), seed=0)
    r = quilt_texture(ex, out_size=(3.0, 3.0), seed=1, boundary="clip")
    rep = r.report
    assert rep.valid and rep.merges["stitched"] >= 6, rep.summary()
    # strands of successive copies became longer strands: 6 + 6 strands cross a
    # 3 x 3 patch; a few may stay in two pieces where a merge was refused
    spans = np.array([np.ptp(r.vertices[np.unique(r.faces[r.element_ids == e])][:, :2],
                             axis=0).max() for e in range(rep.elements)])
    assert (spans > 2.1).sum() >= 6 and rep.elements <= 16
    # every seam is welded (gap 0) and bends the strand less than its own rings
    # do (10.8 degrees on average): measured 8 of 8 welded, jump mean of the
    # merges' maxima 2.0, largest 2.5 degrees (before the tilt-aware cut: 7 of
    # 8 welded, one strip with gap 0.10 of the cell, 11 / 34 degrees)
    assert rep.seam_gap_max == 0.0
    assert rep.seam_normal_jump_mean < 5.0 and rep.seam_normal_jump_max < 10.0
    assert abs(rep.height_mean - rep.exemplar_height_mean) < 0.01
    assert_printable(*_slab_union(r.vertices, r.faces, 3.0, 3.0))


def test_quilted_weave_same_seed_same_bytes():
    from geotex.exemplars import exemplar
    ex = exemplar("weave", size=(2.0, 1.5), seed=2)
    a = quilt_texture(ex, out_size=(3.0, 2.0), seed=5, boundary="clip")
    b = quilt_texture(ex, out_size=(3.0, 2.0), seed=5, boundary="clip")
    assert a.report.merges["stitched"] > 0                  # the merge path ran
    assert a.vertices.tobytes() == b.vertices.tobytes()
    assert a.faces.tobytes() == b.faces.tobytes()
    assert a.element_ids.tobytes() == b.element_ids.tobytes()


def test_quilted_chain_mail_copies_land_on_its_lattice():
    from geotex.exemplars import exemplar
    ex = exemplar("chainmail", size=(2.0, 2.0), seed=0, resolution=12, wire=0.07)
    r = quilt_texture(ex, out_size=(3.0, 2.5), seed=0, boundary="clip")
    rep = r.report
    assert rep.cell == pytest.approx([3.0 / round(3.0 / ex.period[0]),
                                      2.5 / round(2.5 / ex.period[1])])
    assert rep.valid, rep.summary()
    # every copy's ring either coincides with a ring already there (absorbed) or
    # links in without touching: nothing had to be dropped
    assert sum(rep.dropped.values()) == 0 and rep.merges["dropped"] == 0
    assert rep.elements >= 50


def test_quilt_cell_pair_and_errors():
    V, F = texture("studs")
    r = quilt_texture(V, F, size=(1.5, 1.5), out_size=(2.0, 1.5), cell=(0.5, 0.375), seed=0)
    assert r.report.cells == [4, 4] and r.report.cell == [0.5, 0.375]
    for bad in ((0.5, 0.0), (0.1, 0.2, 0.3), "x", float("nan")):
        with pytest.raises(InputError, match="cell"):
            quilt_texture(V, F, size=(1.5, 1.5), out_size=(2.0, 1.5), cell=bad)


# ----------------------------------------------------------------------------
# the quality report's measures

def test_coverage_fraction_and_element_stats():
    from geotex.quilting.quality import coverage_fraction, element_stats
    V, F = box((0.0, 0.0, -0.1), (1.0, 0.5, 0.2))
    assert coverage_fraction(V, F, (0, 0, 2, 1), resolution=400) == pytest.approx(0.25, abs=0.01)
    V2 = np.r_[V, V * [0.5, 1, 1] + [1.2, 0.2, 0]]
    F2 = np.r_[F, F + len(V)]
    ids = np.r_[np.zeros(len(F), np.int64), np.ones(len(F), np.int64)]
    st = element_stats(V2, F2, ids)
    assert st["footprint_mean"] == pytest.approx((0.75 + 0.5) / 2)
    assert st["height_mean"] == pytest.approx(0.2) and st["height_std"] == pytest.approx(0)


def test_report_counts_crossing_and_nested_elements():
    from geotex.quilting import quilt_report
    big, F = stud((0.5, 0.5), r=0.3, height=0.3)
    small, _ = stud((0.5, 0.5), r=0.05, height=0.05, depth=0.01)       # inside big
    apart, _ = stud((1.5, 0.5))
    crossing, _ = stud((0.75, 0.5))                                    # crosses big's surface

    def report(*parts):
        V = np.concatenate(parts)
        FF = np.concatenate([F + i * len(big) for i in range(len(parts))])
        ids = np.repeat(np.arange(len(parts)), len(F))
        return quilt_report(V, FF, ids, exemplar=(big, F, (1.0, 1.0)), domain=(0, 0, 2, 1),
                            merges={}, dropped={}, seams=[], placements=0, icp_iterations=0,
                            cells=(1, 1), cell=(1.0, 1.0))

    ok = report(big, apart)
    assert ok.valid and ok.nested_element_pairs == 0 and ok.intersecting_element_pairs == 0
    nested = report(big, small, apart)
    assert nested.nested_element_pairs == 1 and nested.intersecting_element_pairs == 0
    assert not nested.valid and "1 nested" in nested.summary()
    cross = report(big, crossing)
    assert cross.intersecting_element_pairs == 1 and cross.nested_element_pairs == 0
    assert not cross.valid


# ----------------------------------------------------------------------------
# the quilting loop

def _slab_union(V, F, W, H):
    solid = manifold_of(*box((0, 0, -0.2), (W, H, 0.0)))
    return arrays_of_manifold(solid + manifold_of(V, F))


def test_quilt_doubles_texture_valid_and_printable():
    V, F = texture("studs")
    r = quilt_texture(V, F, size=(1.5, 1.5), out_size=(3.0, 1.5), seed=1)
    rep = r.report
    assert rep.elements >= 8 and rep.bad_elements == 0
    assert rep.self_intersecting_elements == 0 and rep.intersecting_element_pairs == 0
    assert rep.valid
    lo, hi = r.vertices.min(axis=0), r.vertices.max(axis=0)
    assert lo[0] >= 0 and lo[1] >= 0 and hi[0] <= 3.0 and hi[1] <= 1.5
    assert r.element_ids.max() + 1 == rep.elements
    assert abs(rep.footprint_mean - rep.exemplar_footprint_mean) < 0.1
    assert 0.5 * rep.exemplar_coverage < rep.coverage <= 1
    assert_printable(*_slab_union(r.vertices, r.faces, 3.0, 1.5))
    d = rep.to_dict()
    assert d["elements"] == rep.elements and "synthesis" in d["timings"]
    assert "elements" in rep.summary()


def test_quilt_same_seed_same_bytes():
    V, F = texture("studs", seed=2)
    a = quilt_texture(V, F, size=(1.5, 1.5), out_size=(2.5, 2.0), seed=7)
    b = quilt_texture(V, F, size=(1.5, 1.5), out_size=(2.5, 2.0), seed=7)
    assert a.vertices.tobytes() == b.vertices.tobytes()
    assert a.faces.tobytes() == b.faces.tobytes()


def test_quilt_strands_and_exemplar_object():
    V, F = texture("strands", size=(2.0, 2.0), pitch=0.5)
    r = quilt_texture(FakeExemplar(V, F, (2.0, 2.0)), out_size=(3.0, 3.0), seed=0)
    assert r.report.valid and r.report.elements >= 9
    assert check_mesh(r.vertices, r.faces, self_intersections=False).watertight


def test_quilt_constrained_frame_fixed_and_domain():
    W = H = 2.0
    # a frame of studs straddling the domain edges; vertices outside the
    # domain or on the edge lines are fixed
    parts = [stud((x, 0.0)) for x in (0.5, 1.5)] + [stud((0.0, y)) for y in (0.5, 1.5)]
    Vp = np.concatenate([p[0] for p in parts])
    Fp = np.concatenate([p[1] + i * len(parts[0][0]) for i, p in enumerate(parts)])
    fixed = (Vp[:, 0] <= 0.02) | (Vp[:, 1] <= 0.02)
    V, F = texture("studs")
    r = quilt_texture(V, F, size=(1.5, 1.5), out_size=(W, H), seed=3, prefilled=(Vp, Fp),
                      fixed=fixed, occupied=[(0.0, 0.0, W, 0.2), (0.0, 0.0, 0.2, H)])
    rep = r.report
    assert rep.valid and rep.prefilled_elements == 4
    # fixed vertices come back bit-exact, all of them
    assert {tuple(p) for p in r.vertices[r.fixed]} == {tuple(p) for p in Vp[fixed]}
    assert r.fixed.sum() == fixed.sum()
    # everything that is not prefilled stays inside the domain
    prefilled_ids = np.unique(r.element_ids[:Fp.shape[0]])
    assert prefilled_ids.tolist() == [0, 1, 2, 3]
    assert r.element_prefilled.tolist() == [True] * 4 + [False] * (rep.elements - 4)
    new = np.unique(r.faces[~np.isin(r.element_ids, prefilled_ids)])
    P = r.vertices[new]
    assert P.size and (P[:, :2] >= 0).all() and (P[:, 0] <= W).all() and (P[:, 1] <= H).all()


def test_quilt_input_errors():
    V, F = texture("studs")
    with pytest.raises(InputError, match="out_size"):
        quilt_texture(V, F, size=(1.5, 1.5), out_size=(0, 2))
    with pytest.raises(InputError, match="size"):
        quilt_texture(V, F, out_size=(2, 2))
    with pytest.raises(InputError, match="larger than the exemplar"):
        quilt_texture(V, F, size=(1.5, 1.5), out_size=(4, 4), cell=2.0)
    with pytest.raises(InputError, match="fixed"):
        quilt_texture(V, F, size=(1.5, 1.5), out_size=(2, 2), fixed=[0])
    with pytest.raises(InputError, match="occupied"):
        quilt_texture(V, F, size=(1.5, 1.5), out_size=(2, 2), occupied=[(1, 1, 0, 0)])
    with pytest.raises(InputError, match="not a closed solid"):
        quilt_texture(V, F[1:], size=(1.5, 1.5), out_size=(2, 2))
    Vh, Fh = stud((1.0, 1.0))
    with pytest.raises(InputError, match="open away from the domain"):
        quilt_texture(V, F, size=(1.5, 1.5), out_size=(2, 2), prefilled=(Vh, Fh[1:]))


def _open_half(center, axis):
    """A stud cut by the plane ``coordinate[axis] = 0``, kept on the positive side, open there."""
    V, F = stud(center)
    lo = [-5.0, -5.0, -1.0]
    lo[axis] = 0.0
    solid = manifold_of(V, F) ^ manifold_of(*box(tuple(lo), (5.0, 5.0, 1.0)))
    V, F = arrays_of_manifold(solid)
    on = (np.abs(V[F][:, :, axis]) <= 1e-12).all(axis=1)
    F = F[~on]
    used = np.unique(F)
    remap = np.zeros(len(V), np.int64)
    remap[used] = np.arange(used.size)
    return V[used], remap[F]


def test_quilt_open_frame_elements_cut_by_the_domain_sides():
    W = H = 2.0
    parts = [_open_half((x, 0.0), 1) for x in (0.5, 1.5)] + \
        [_open_half((0.0, y), 0) for y in (0.7, 1.4)]
    Vp = np.concatenate([p[0] for p in parts])
    offs = np.cumsum([0] + [len(p[0]) for p in parts])
    Fp = np.concatenate([p[1] + o for p, o in zip(parts, offs)])
    cut = (np.abs(Vp[:, 0]) <= 1e-12) | (np.abs(Vp[:, 1]) <= 1e-12)
    for V, F in parts:      # precondition: open only on the sides, valid once capped
        F2, cap, on_cut = capped(V, F, (0, 0, W, H))
        assert cap.any() and closed_element_ok(V, F2) == ""
    V, F = texture("studs")
    r = quilt_texture(V, F, size=(1.5, 1.5), out_size=(W, H), seed=5, prefilled=(Vp, Fp))
    assert r.report.valid and r.report.prefilled_elements == 4
    # the cut vertices are fixed automatically and come back bit-exact
    assert {tuple(p) for p in r.vertices[r.fixed]} >= {tuple(p) for p in Vp[cut]}
    # the output stays open exactly along the domain sides, closed elsewhere
    rep = check_mesh(r.vertices, r.faces, self_intersections=False)
    assert rep.boundary_edges > 0
    from geotex.mesh.topology import edge_topology
    topo = edge_topology(r.faces, len(r.vertices))
    B = r.vertices[topo.edges[topo.boundary].ravel()]
    assert ((np.abs(B[:, 0]) <= 1e-12) | (np.abs(B[:, 1]) <= 1e-12)).all()
    assert r.report.elements > 4


@pytest.mark.parametrize("align", [False, True])
def test_merge_into_an_open_frame_element_keeps_its_cut(align):
    V, F = _open_half((0.5, 0.0), 1)
    F2, cap, on_cut = capped(V, F, (0, 0, 2, 2))
    VB, FB = stud((0.62, 0.12), r=0.14)
    r = merge_elements(V, F2, VB, FB, fixed_a=on_cut, cap_a=cap, domain=(0, 0, 2, 2),
                       align=align)
    assert r.status in ("stitched", "union"), r.reason
    assert closed_element_ok(r.vertices, r.faces) == ""
    # the caps come back marked; without them the opening is the original cut, bit-exact
    assert r.cap.sum() > 0
    assert {tuple(p) for p in r.vertices[r.fixed]} == {tuple(p) for p in V[on_cut]}
    from geotex.mesh.topology import edge_topology
    topo = edge_topology(r.faces[~r.cap], len(r.vertices))
    B = np.unique(topo.edges[topo.boundary])
    assert {tuple(p) for p in r.vertices[B]} == {tuple(p) for p in V[on_cut]}


def test_touching_detects_copies_contacts_and_crossings():
    from geotex.quilting.elements import Element
    from geotex.quilting.placement import touching
    V, F = stud((0, 0))
    e = Element(V, F, np.zeros(len(V), bool))
    def at(dx, dy=0.0):
        return Element(V + [dx, dy, 0], F, np.zeros(len(V), bool))
    assert touching(e, at(0.0))            # an exact copy (winding number 1/2 only)
    assert touching(e, at(0.2))            # overlapping
    assert not touching(e, at(0.4))        # apart (radius 0.16)
    R, RF = icosphere(2)
    thin = Element(R * [0.02, 0.6, 0.02] + [0.0, 0.0, 0.3], RF, np.zeros(len(R), bool))
    assert not touching(e, thin)           # passes above the stud
    thin2 = Element(R * [0.02, 0.6, 0.02] + [0.0, 0.0, 0.1], RF, np.zeros(len(R), bool))
    assert touching(e, thin2)              # a rod through the dome
    from geotex.quilting.placement import coincides
    assert coincides(e, at(0.0)) and coincides(e, at(0.003))     # copies in place
    assert not coincides(e, at(0.05)) and not coincides(e, at(0.0, 0.05))
    big = Element(V * [1.2, 1.2, 1.0], F, np.zeros(len(V), bool))
    assert not coincides(e, big)


@pytest.mark.parametrize("offset, r", [((0.13, 0.0), 0.16), ((0.09, 0.09), 0.15),
                                       ((0.0, 0.0), 0.22)])
def test_merge_refuses_neighbouring_elements_that_only_look_alike(offset, r):
    # the pairs the tile builder used to fuse into two-bump elements (normal
    # jumps of 130-180 degrees at their seams): a neighbouring stud that ICP
    # can slide onto A (shift 0.41-0.43 of its width), and a wider stud in
    # the same place (shift 0, but the surfaces do not coincide)
    VA, FA = stud((0.0, 0.0))
    VB, FB = stud(offset, r=r)
    r = merge_elements(VA, FA, VB, FB, corresponding_only=True)
    assert r.status == "dropped" and not r.corresponding
    assert np.array_equal(r.vertices, VA) and np.array_equal(r.faces, FA)
    # unaligned (the retry after a collision) it does not fuse them either
    u = merge_elements(VA, FA, VB, FB, align=False, corresponding_only=True)
    assert u.status == "dropped"


def test_merge_of_a_frame_half_with_the_copy_of_its_element_keeps_the_half():
    # the copy goes on beyond the tile side (x = 0): inside the tile it adds
    # nothing, whatever its part outside; a small offset is aligned away
    V, F = _open_half((0.05, 0.3), 0)
    F2, cap, on_cut = capped(V, F, (0, 0, 1, 1))
    for dx in (0.0, 0.012):
        VB, FB = stud((0.05 + dx, 0.3 - dx))
        r = merge_elements(V, F2, VB, FB, fixed_a=on_cut, cap_a=cap, domain=(0, 0, 1, 1),
                           corresponding_only=True)
        assert r.status == "absorbed", (dx, r.status, r.reason)
        assert np.array_equal(r.vertices, V) and np.array_equal(r.faces, F2)


@pytest.mark.parametrize("corner", [(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)])
def test_capped_closes_an_element_cut_at_a_domain_corner(corner):
    # a dome on a domain corner, cut by both lines through it: each quarter is
    # open along two planes meeting at the corner; capped closes it with two
    # caps sharing the corner edge, and the four quarters make up the dome
    from geotex.tiles.clip import split_by_plane
    V, F = icosphere(3)
    # (off the corner a little: the sphere's poles would lie on both cut lines)
    V = V * [0.14, 0.14, 0.2] + [corner[0] + 0.013, corner[1] - 0.007, 0.0]
    total = 0.0
    for Vh, Fh in split_by_plane(V, F, axis=0, value=corner[0], snap=1e-4):
        for Vq, Fq in split_by_plane(Vh, Fh, axis=1, value=corner[1], snap=1e-4,
                                     ordered=True):
            F2, cap, on_cut = capped(Vq, Fq, (0, 0, 2, 2))
            assert cap.sum() > 0 and closed_element_ok(Vq, F2, intersections=False) == ""
            total += signed_volume(Vq, F2)
    assert total == pytest.approx(signed_volume(V, F), rel=1e-3)
    # a loop along two sides that does not pass their corner line is refused
    Vs = Vq.copy()
    Vs[on_cut & (Vs[:, 2] > 0.1), :2] += 0.01
    with pytest.raises(InputError, match="open away"):
        capped(Vs, Fq, (0, 0, 2, 2))
