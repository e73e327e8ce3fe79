import numpy as np

from geotex.mesh.polygons import polygon_triangle_corners


def signed_areas(P, corners, normal=(0, 0, 1)):
    a, b, c = P[corners[:, 0]], P[corners[:, 1]], P[corners[:, 2]]
    return 0.5 * np.cross(b - a, c - a) @ np.asarray(normal, float)


def test_non_convex_polygons_are_covered_without_overlap():
    L = [[0, 0, 0], [2, 0, 0], [2, 1, 0], [1, 1, 0], [1, 2, 0], [0, 2, 0]]   # area 3
    dart = [[0, 0, 0], [2, 1, 0], [0, 2, 0], [0.5, 1, 0]]                  # area 1.5
    comb = [[0, 0, 0], [5, 0, 0], [5, 3, 0], [4, 3, 0], [4, 1, 0], [3, 1, 0], [3, 3, 0],
            [2, 3, 0], [2, 1, 0], [1, 1, 0], [1, 3, 0], [0, 3, 0]]        # area 5 + 3*2 = 11
    P = np.array(L + dart + comb, dtype=float)
    corners, dropped = polygon_triangle_corners([6, 4, 12], P)
    assert dropped == 0 and corners.shape == (4 + 2 + 10, 3)
    A = signed_areas(P, corners)
    assert np.all(A > 0)  # all triangles keep the polygon's orientation: no overlap
    assert np.isclose(A[:4].sum(), 3) and np.isclose(A[4:6].sum(), 1.5)
    assert np.isclose(A[6:].sum(), 11)


def test_triangles_pass_through_and_short_polygons_drop():
    P = np.random.default_rng(1).random((3 + 2 + 3, 3))
    corners, dropped = polygon_triangle_corners([3, 2, 3], P)
    assert dropped == 1 and corners.tolist() == [[0, 1, 2], [5, 6, 7]]


def test_tilted_polygon_in_3d():
    t = np.linspace(0, 2 * np.pi, 9)[:-1]
    r = np.where(np.arange(8) % 2, 0.4, 1.0)  # a star: non-convex
    P2 = np.stack([r * np.cos(t), r * np.sin(t), np.zeros(8)], 1)
    R = np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))[0]
    if np.linalg.det(R) < 0:
        R[:, 0] *= -1
    P = P2 @ R.T
    corners, _ = polygon_triangle_corners([8], P)
    A = signed_areas(P2, corners)
    area = 0.5 * np.sum(P2[:, 0] * np.roll(P2[:, 1], -1) - np.roll(P2[:, 0], -1) * P2[:, 1])
    assert np.all(A > 0) and np.isclose(A.sum(), area)


def test_straight_angle_corners_give_no_flat_triangles():
    # a triangle with a vertex in the middle of every side (as CAD exports write)
    P = np.array([[7.5, 12.5, -7.5], [10, 10, -10], [5, 10, -10], [0, 10, -10],
                  [2.5, 12.5, -7.5], [5, 15, -5]], dtype=float)
    corners, _ = polygon_triangle_corners([6], P)
    n = np.cross(P[corners[:, 1]] - P[corners[:, 0]], P[corners[:, 2]] - P[corners[:, 0]])
    areas = np.linalg.norm(n, axis=1) / 2
    total = np.linalg.norm(np.cross(P[3] - P[1], P[5] - P[1])) / 2
    assert np.all(areas > 1e-6 * total) and np.isclose(areas.sum(), total)
    normal = n / np.linalg.norm(n, axis=1, keepdims=True)
    assert np.allclose(normal, normal[0])  # all keep the polygon's orientation
