"""Closest points in the polycube fit: libigl's AABB against a compiled BVH prototype.

The polycube fit (``geotex/param/polycube_fit.py``) projects the same few
thousand points onto the base some 200 times per shell, each round from
where the last round left them (``SurfaceProjector.closest``, libigl's
``AABB.squared_distance``, tree built once per base). This script builds
the shells of the benchmark bases three ways, each in its own process, and
reports the CPU seconds spent in those queries and what the shell came out as:

* ``igl``: geotex as it is;
* ``bvh``: a numba BVH (median split on the longest axis, 2-4 faces per leaf,
  nearer child first) with the previous round's face as a warm start;
  exact (every face whose box is not farther than the best is tested);
* ``bvh-exit``: the same, but a point within 1e-13 of the box diagonal of a
  face stops the search there (the answer is within that distance of exact).

Ties (a point closest to an edge or vertex shared by several faces) go to
another face than libigl's, so the fit, and everything after it, changes.
Results: ``benchmarks/results/start_shell.md``.

Usage: ``python benchmarks/closest_points.py BASE.obj [...]`` (bases are
scaled to 80 mm as ``geotex texture --size-mm 80``).
"""

from __future__ import annotations

import json
import subprocess
import sys
import time

import numba
import numpy as np


#: Faces per leaf of the tree (2-4: the tree is complete).
LEAF_SIZE = 4
#: ``bvh-exit``: a point this close to a face (relative to the mesh's box diagonal) is on it.
TOLERANCE = 1e-13


class ClosestPointTree:
    """Closest points on a fixed triangle mesh (see the module notes).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        At least one face; indices in range (not checked again here).

    """

    early_exit = True

    def __init__(self, V, F):
        self.V = np.ascontiguousarray(V, dtype=np.float64)
        self.F = np.ascontiguousarray(F, dtype=np.int64)
        m = self.F.shape[0]
        T = self.V[self.F]                                      # (m, 3, 3)
        C = T.mean(axis=1)
        depth = max(0, (-(-m // LEAF_SIZE) - 1).bit_length())
        P = 1 << depth                                          # leaves: a complete tree
        start = (np.arange(P + 1) * m) // P                     # faces of leaf k: a range
        leaf_of = np.repeat(np.arange(P), np.diff(start))       # leaf of each position
        order = np.arange(m)
        for level in range(depth):        # median split along each node's longest axis
            node = leaf_of >> (depth - level)
            first = start[np.arange(1 << level) << (depth - level)]
            c = C[order]
            ext = np.maximum.reduceat(c, first, axis=0) - np.minimum.reduceat(c, first, axis=0)
            axis = np.argmax(ext, axis=1)
            order = order[np.lexsort((c[np.arange(m), axis[node]], node))]
        tlo, thi = T.min(axis=1)[order], T.max(axis=1)[order]
        lo = np.empty((2 * P, 3))
        hi = np.empty((2 * P, 3))
        lo[P:] = np.minimum.reduceat(tlo, start[:-1], axis=0)
        hi[P:] = np.maximum.reduceat(thi, start[:-1], axis=0)
        k = P
        while k > 1:                                           # heap order: children 2i, 2i+1
            h = k // 2
            lo[h:k] = np.minimum(lo[k:2 * k:2], lo[k + 1:2 * k:2])
            hi[h:k] = np.maximum(hi[k:2 * k:2], hi[k + 1:2 * k:2])
            k = h
        self._order, self._start, self._lo, self._hi, self._leaves = order, start, lo, hi, P
        diag2 = float(((T.max(axis=(0, 1)) - T.min(axis=(0, 1))) ** 2).sum())
        self._tol2 = TOLERANCE ** 2 * diag2
        self._where = np.empty(m, dtype=np.int64)              # face -> position in order
        self._where[order] = np.arange(m)
        self._T = np.ascontiguousarray(T[order])

    def closest(self, X, hint=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Closest points of the mesh to the points ``X``.

        Parameters
        ----------
        X : array_like, (k, 3) float64
        hint : array_like, (k,) int64, optional
            A face per point whose distance bounds the search first (any face:
            a good guess only makes the search faster).

        Returns
        -------
        points : numpy.ndarray, (k, 3) float64
        faces : numpy.ndarray, (k,) int64
        sqr_distances : numpy.ndarray, (k,) float64
        """
        X = np.ascontiguousarray(X, dtype=np.float64).reshape(-1, 3)
        k = X.shape[0]
        if hint is None:
            hint = np.full(k, -1, dtype=np.int64)
        else:
            hint = np.ascontiguousarray(hint, dtype=np.int64).reshape(k)
        points = np.empty((k, 3))
        faces = np.empty(k, dtype=np.int64)
        d2 = np.empty(k)
        _closest_loops(X, hint, self._T, self._order, self._where, self._start, self._lo,
                       self._hi, self._leaves, self._tol2 if self.early_exit else -1.0,
                       points, faces, d2)
        return points, faces, d2


@numba.njit(cache=True, nogil=True)
def _point_triangle(x, y, z, T, f, out):
    """Closest point of triangle ``T[f]`` to ``(x, y, z)`` into ``out``; its squared distance.

    The operations of :func:`closest_points_on_triangles`, one triangle.
    """
    ax, ay, az = T[f, 0, 0], T[f, 0, 1], T[f, 0, 2]
    bx, by, bz = T[f, 1, 0], T[f, 1, 1], T[f, 1, 2]
    cx, cy, cz = T[f, 2, 0], T[f, 2, 1], T[f, 2, 2]
    abx, aby, abz = bx - ax, by - ay, bz - az
    acx, acy, acz = cx - ax, cy - ay, cz - az
    apx, apy, apz = x - ax, y - ay, z - az
    bpx, bpy, bpz = x - bx, y - by, z - bz
    cpx, cpy, cpz = x - cx, y - cy, z - cz
    d1 = abx * apx + aby * apy + abz * apz
    d2 = acx * apx + acy * apy + acz * apz
    d3 = abx * bpx + aby * bpy + abz * bpz
    d4 = acx * bpx + acy * bpy + acz * bpz
    d5 = abx * cpx + aby * cpy + abz * cpz
    d6 = acx * cpx + acy * cpy + acz * cpz
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    if d1 <= 0 and d2 <= 0:
        px, py, pz = ax, ay, az
    elif d3 >= 0 and d4 <= d3:
        px, py, pz = bx, by, bz
    elif vc <= 0 and d1 >= 0 and d3 <= 0:
        t = d1 / (d1 - d3)
        px, py, pz = ax + t * abx, ay + t * aby, az + t * abz
    elif d6 >= 0 and d5 <= d6:
        px, py, pz = cx, cy, cz
    elif vb <= 0 and d2 >= 0 and d6 <= 0:
        t = d2 / (d2 - d6)
        px, py, pz = ax + t * acx, ay + t * acy, az + t * acz
    elif va <= 0 and d4 - d3 >= 0 and d5 - d6 >= 0:
        t = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        px, py, pz = bx + t * (cx - bx), by + t * (cy - by), bz + t * (cz - bz)
    else:
        den = va + vb + vc
        v, w = vb / den, vc / den
        px, py, pz = ax + v * abx + w * acx, ay + v * aby + w * acy, az + v * abz + w * acz
    if not (np.isfinite(px) and np.isfinite(py) and np.isfinite(pz)):
        best = np.inf                            # degenerate triangle: nearest corner
        for c in range(3):
            qx, qy, qz = T[f, c, 0], T[f, c, 1], T[f, c, 2]
            d = (qx - x) ** 2 + (qy - y) ** 2 + (qz - z) ** 2
            if d < best:
                best, px, py, pz = d, qx, qy, qz
    out[0], out[1], out[2] = px, py, pz
    return (px - x) ** 2 + (py - y) ** 2 + (pz - z) ** 2


@numba.njit(cache=True, nogil=True)
def _box_distance(x, y, z, lo, hi, node):
    """Squared distance from ``(x, y, z)`` to the box of ``node`` (0 inside)."""
    d = 0.0
    if x < lo[node, 0]:
        d += (lo[node, 0] - x) ** 2
    elif x > hi[node, 0]:
        d += (x - hi[node, 0]) ** 2
    if y < lo[node, 1]:
        d += (lo[node, 1] - y) ** 2
    elif y > hi[node, 1]:
        d += (y - hi[node, 1]) ** 2
    if z < lo[node, 2]:
        d += (lo[node, 2] - z) ** 2
    elif z > hi[node, 2]:
        d += (z - hi[node, 2]) ** 2
    return d


@numba.njit(cache=True, nogil=True)
def _closest_loops(X, hint, T, order, where, start, lo, hi, leaves, tol2, points, faces, d2):
    """:meth:`ClosestPointTree.closest`, point by point (depth-first, nearer child first).

    ``T`` holds the triangles in tree order: ``T[s]`` is face ``order[s]``
    (``where`` the inverse); the search works on positions and reports faces.
    """
    stack = np.empty(128, dtype=np.int64)
    cand = np.empty(3)
    for i in range(X.shape[0]):
        x, y, z = X[i, 0], X[i, 1], X[i, 2]
        best, pos = np.inf, -1
        bx, by, bz = np.nan, np.nan, np.nan
        if hint[i] >= 0:
            pos = where[hint[i]]
            best = _point_triangle(x, y, z, T, pos, cand)
            bx, by, bz = cand[0], cand[1], cand[2]
        top = 0 if best > tol2 else -1            # on the hint face: nothing is closer
        stack[0] = 1
        while top >= 0:
            node = stack[top]
            top -= 1
            if _box_distance(x, y, z, lo, hi, node) >= best:
                continue
            if node >= leaves:
                for s in range(start[node - leaves], start[node - leaves + 1]):
                    if s == pos:
                        continue
                    d = _point_triangle(x, y, z, T, s, cand)
                    if d < best or pos < 0:
                        best, pos, bx, by, bz = d, s, cand[0], cand[1], cand[2]
                if best <= tol2:
                    break
                continue
            left, right = 2 * node, 2 * node + 1
            if _box_distance(x, y, z, lo, hi, left) <= _box_distance(x, y, z, lo, hi, right):
                stack[top + 1], stack[top + 2] = right, left     # the nearer popped first
            else:
                stack[top + 1], stack[top + 2] = left, right
            top += 2
        points[i, 0], points[i, 1], points[i, 2] = bx, by, bz
        faces[i], d2[i] = order[pos], best


def _one(base: str, variant: str) -> dict:
    import geotex.param.polycube_fit as pf
    from geotex.io import read_mesh
    from geotex.shells import build_shell

    spent = [0.0, 0]
    if variant != "igl":
        ClosestPointTree.early_exit = variant == "bvh-exit"

        def init(self, V, F):
            self.V = np.ascontiguousarray(V, dtype=np.float64)
            self.F = np.ascontiguousarray(F, dtype=np.int64)
            self.normals = pf.face_normals(self.V, self.F)
            self._tree = ClosestPointTree(self.V, self.F)
            self._kd = None

        def closest(self, X, hint=None):
            C, face, _ = self._tree.closest(X, hint)
            return C, face

        pf.SurfaceProjector.__init__ = init
        # the fit loop passes no hint; remember each projector's last faces per size
        last: dict = {}

        def hinted(self, X, hint=None):
            key = (id(self), X.shape[0])
            C, face = closest(self, X, last.get(key))
            last[key] = face
            return C, face

        pf.SurfaceProjector.closest = hinted
        ClosestPointTree(np.eye(3), np.array([[0, 1, 2]])).closest(np.zeros((1, 3)))  # compile
    timed = pf.SurfaceProjector.closest

    def counted(self, X, hint=None):
        t = time.process_time()
        out = timed(self, X)
        spent[0] += time.process_time() - t
        spent[1] += X.shape[0]
        return out

    pf.SurfaceProjector.closest = counted
    mesh = read_mesh(base)
    V = mesh.vertices * (80.0 / float(np.ptp(mesh.vertices, axis=0).max()))
    build_shell(V, mesh.faces, tile_size=None, name="x")           # numba, caches warm
    spent[:] = [0.0, 0]
    t = time.process_time()
    sh = build_shell(V, mesh.faces, tile_size=None, name="x")
    total = time.process_time() - t
    return {"base": base, "variant": variant, "closest_cpu": spent[0], "points": spent[1],
            "shell_cpu": total, "quads": sh.n_quads,
            "bare": int(sh.polycube.quad_folded.sum()), "max_height": sh.max_height,
            "area_mean": sh.distortion["area_mean"], "angle_mean": sh.distortion["angle_mean"],
            "within_quarter_tile": sh.polycube.diagnostics.coverage["within_quarter_tile"]}


def main(argv=None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if args and args[0] == "--one":
        print(json.dumps(_one(args[1], args[2])))
        return 0
    for base in args:
        for variant in ("igl", "bvh", "bvh-exit"):
            out = subprocess.run([sys.executable, __file__, "--one", base, variant],
                                 capture_output=True, text=True, check=True)
            r = json.loads(out.stdout.strip().splitlines()[-1])
            print(f"{base} {variant:8s} closest {r['closest_cpu']:.3f} s CPU for {r['points']} "
                  f"points, shell {r['shell_cpu']:.2f} s CPU; {r['quads']} quads "
                  f"({r['bare']} bare), safe height {r['max_height']:.4g}, distortion "
                  f"{r['area_mean']:.4f} / {r['angle_mean']:.4f}, "
                  f"{100 * r['within_quarter_tile']:.2f} % within 1/4 tile")
    return 0


if __name__ == "__main__":
    sys.exit(main())
