"""One paste operation: grow a surface patch over a texture patch and flatten it.

Lapped textures §3.3-3.4, built on :func:`geotex.patches.grow_patch` and
:func:`geotex.param.local.field_aligned_parameterization`:

1. The seed face is mapped so the seed point lands on the patch centre and
   the face's frame (right ``S = T x N``, up ``T``) on the texture axes, at
   the local scale (surface length per texture unit).
2. The patch grows face by face in order of distance (disc topology kept by
   ``grow_patch``).  As a face joins, its direction is set (the field's
   representative closest to the patch neighbours' average, or, for
   isotropic pastes, that average projected into the face: the paper's
   propagation) and its new vertex gets texture coordinates by **triangle
   extension** (the face unfolded over its mapped edge, Maillot et al.).
   A neighbour is admitted only over an edge whose image still meets the
   texture patch's polygon hull (:class:`geotex.image.hull.HullTest`), and
   only inside a normal cone about the seed normal.
3. The field-aligned least squares replaces the initial map.  When a
   growable boundary edge of the optimized map still meets the hull (the
   optimization uncovered texture; the hull shrunk by ``REGROW_MARGIN``
   towards the centre is tested), the patch is grown again with the
   optimized coordinates kept for the faces it already has, and optimized
   again (at most ``rounds`` times, and only while the face set changes).
4. Faces whose final map is flipped or stretched beyond ``max_stretch`` are
   dropped (the paper stops growth "when distortion becomes excessive"); the
   paste keeps the seed's edge-connected part of the rest.  When that would
   drop the seed face or more than half of the patch (a paste centred on a field singularity,
   where no map can follow the field), only flipped faces are dropped: such
   pastes are placed early and covered over later, as in the paper.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

from geotex.image.hull import HullTest, segments_meet_polygon
from geotex.image.patches import TexturePatch
from geotex.image.records import Paste
from geotex.param.distortion import face_jacobians, singular_values
from geotex.param.local import field_aligned_parameterization
from geotex.patches.grow import grow_patch

__all__ = ["Paster", "REGROW_MARGIN"]

#: A patch is grown again only when its optimized boundary cuts into the hull
#: shrunk by this fraction towards the centre (texture lost at the rim is
#: covered by other pastes anyway).
REGROW_MARGIN = 0.1


class Paster:
    """Reusable state for many paste operations on one mesh.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        Validated arrays (no degenerate faces).
    adjacency : geotex.patches.grow.FaceAdjacency
    frames : tuple of numpy.ndarray
        ``(T1, T2, N)`` face frames, each ``(m, 3)``.
    up : numpy.ndarray, (m, 3) float64 or None
        Unit tangent "up" field (one representative per face), or ``None``
        for isotropic pastes (direction propagated from a random one).
    symmetry : int
        ``N`` of the field (1, 2, 4, ...).
    scale : numpy.ndarray, (m,) float64
        Surface length of one texture unit per face.
    max_normal_angle : float
        Normal cone half-angle (radians) about the seed normal.
    max_stretch : float
        Largest singular-value ratio kept after optimization.
    rounds : int
        Grow-and-optimize rounds at most.
    max_faces : int
        Cap on the faces of one surface patch.
    """

    def __init__(self, V, F, adjacency, frames, *, up, symmetry, scale, max_normal_angle,
                 max_stretch, rounds, max_faces):
        self.V, self.F, self.adj = V, F, adjacency
        self.T1, self.T2, self.N = frames
        self.up = up
        self.sym = int(symmetry)
        self.scale = scale
        self.cos_limit = math.cos(max_normal_angle) - 1e-12
        self.max_stretch = float(max_stretch)
        self.rounds = int(rounds)
        self.max_faces = int(max_faces)
        n, m = V.shape[0], F.shape[0]
        self._V = V.tolist()
        self._F = F.tolist()
        self._N = self.N.tolist()
        self._FF = adjacency.face_neighbors.tolist()
        self._up = None if up is None else up.tolist()
        self._upx = None if up is None else np.cross(self.N, up).tolist()  # N x up
        self._ux = [0.0] * n
        self._uy = [0.0] * n
        self._vstamp = [0] * n
        self._fstamp = [0] * m
        self._dir = [None] * m
        self._stamp = 0
        self._right = np.zeros((m, 3))

    # ------------------------------------------------------------------ growth

    def _choose_direction(self, f: int, ax: float, ay: float, az: float) -> list:
        n = self._N[f]
        if self._up is None:
            d = ax * n[0] + ay * n[1] + az * n[2]
            x, y, z = ax - d * n[0], ay - d * n[1], az - d * n[2]
            ll = math.sqrt(x * x + y * y + z * z)
            if ll == 0.0:
                t = self.T1[f]
                return [float(t[0]), float(t[1]), float(t[2])]
            return [x / ll, y / ll, z / ll]
        u = self._up[f]
        if self.sym == 1:
            return u
        w = self._upx[f]
        cu = ax * u[0] + ay * u[1] + az * u[2]
        cw = ax * w[0] + ay * w[1] + az * w[2]
        best = round(math.atan2(cw, cu) / (2.0 * math.pi / self.sym)) % self.sym
        a = 2.0 * math.pi * best / self.sym
        c, s = math.cos(a), math.sin(a)
        return [c * u[0] + s * w[0], c * u[1] + s * w[1], c * u[2] + s * w[2]]

    def _grow(self, seed: int, seed_point, seed_dir, center, h0, hull: HullTest, prev: int):
        stamp = self._stamp = self._stamp + 1
        Vl, Fl, FF, Nl = self._V, self._F, self._FF, self._N
        ux, uy, vst, fst, dirs = self._ux, self._uy, self._vstamp, self._fstamp, self._dir
        sn = Nl[seed]
        cos_limit = self.cos_limit
        last = [seed]
        blocked = set()
        px, py, pz = (float(x) for x in seed_point)
        T = seed_dir
        n0 = Nl[seed]
        S = [T[1] * n0[2] - T[2] * n0[1], T[2] * n0[0] - T[0] * n0[2], T[0] * n0[1] - T[1] * n0[0]]
        cu, cv = float(center[0]), float(center[1])

        def on_join(f: int) -> None:
            was = fst[f] == prev and prev > 0
            fst[f] = stamp
            last[0] = f
            if f == seed:
                if not was:
                    dirs[f] = T
            elif not was:
                ax = ay = az = 0.0
                for g in FF[f]:
                    if g >= 0 and fst[g] == stamp and g != f:
                        d = dirs[g]
                        ax += d[0]
                        ay += d[1]
                        az += d[2]
                dirs[f] = self._choose_direction(f, ax, ay, az)
            fv = Fl[f]
            new = -1
            for k in range(3):
                v = fv[k]
                if vst[v] == stamp:
                    continue
                if vst[v] == prev and prev > 0:
                    vst[v] = stamp
                elif f == seed:
                    x = Vl[v]
                    dx, dy, dz = x[0] - px, x[1] - py, x[2] - pz
                    ux[v] = cu + (dx * S[0] + dy * S[1] + dz * S[2]) / h0
                    uy[v] = cv + (dx * T[0] + dy * T[1] + dz * T[2]) / h0
                    vst[v] = stamp
                else:
                    new = k
            if new >= 0:
                c, a, b = fv[new], fv[(new + 1) % 3], fv[(new + 2) % 3]
                A, B, C = Vl[a], Vl[b], Vl[c]
                n = Nl[f]
                ex, ey, ez = B[0] - A[0], B[1] - A[1], B[2] - A[2]
                wx, wy, wz = C[0] - A[0], C[1] - A[1], C[2] - A[2]
                ll = ex * ex + ey * ey + ez * ez
                al = (wx * ex + wy * ey + wz * ez) / ll
                # n x e
                qx, qy, qz = n[1] * ez - n[2] * ey, n[2] * ex - n[0] * ez, n[0] * ey - n[1] * ex
                be = (wx * qx + wy * qy + wz * qz) / ll
                Ex, Ey = ux[b] - ux[a], uy[b] - uy[a]
                ux[c] = ux[a] + al * Ex - be * Ey
                uy[c] = uy[a] + al * Ey + be * Ex
                vst[c] = stamp

        def accept(ids):
            f = last[0]
            nb = FF[f]
            fv = Fl[f]
            out = np.zeros(ids.shape[0], dtype=bool)
            for i, g in enumerate(ids.tolist()):
                n = Nl[g]
                if n[0] * sn[0] + n[1] * sn[1] + n[2] * sn[2] < cos_limit:
                    blocked.add(g)
                    continue
                k = nb.index(g)
                a, b = fv[k], fv[(k + 1) % 3]
                out[i] = hull.segment(ux[a], uy[a], ux[b], uy[b])
            return out

        patch = grow_patch(self.V, self.F, seed, accept=accept, on_join=on_join,
                           max_faces=self.max_faces, adjacency=self.adj)
        return patch, blocked

    # ------------------------------------------------------------------ paste

    def paste(self, seed: int, seed_bary, patch: TexturePatch, patch_index: int,
              rng: np.random.Generator) -> Paste:
        """Paste ``patch`` centred on the point ``seed_bary`` of face ``seed``.

        Parameters
        ----------
        seed : int
        seed_bary : numpy.ndarray, (3,) float64
            Barycentric coordinates of the centre point in the seed face.
        patch : TexturePatch
        patch_index : int
        rng : numpy.random.Generator
            Draws the seed direction (random angle for isotropic pastes,
            random representative of an N-direction field).

        Returns
        -------
        Paste
        """
        V, F = self.V, self.F
        seed_point = seed_bary @ V[F[seed]]
        if self.up is None:
            phi = float(rng.uniform(0.0, 2.0 * math.pi))
            d = math.cos(phi) * self.T1[seed] + math.sin(phi) * self.T2[seed]
        else:
            k = int(rng.integers(self.sym))
            a = 2.0 * math.pi * k / self.sym
            d = math.cos(a) * self.up[seed] + math.sin(a) * np.cross(self.N[seed], self.up[seed])
        seed_dir = [float(x) for x in d]
        hull = HullTest(patch.hull, patch.center)
        center = patch.center
        h0 = float(self.scale[seed])
        prev = 0
        faces_before = None
        rounds = 0
        while True:
            rounds += 1
            grown, blocked = self._grow(seed, seed_point, seed_dir, center, h0, hull, prev)
            faces = np.asarray(grown.faces)
            dirs = np.array([self._dir[f] for f in faces.tolist()], dtype=np.float64)
            self._right[faces] = np.cross(dirs, self.N[faces])
            uv, verts = field_aligned_parameterization(V, F, faces, self._right,
                                                       scale=self.scale, center_face=seed)
            local = np.searchsorted(verts, F[faces])
            uv += center - seed_bary @ uv[local[0]]
            stamp = self._stamp
            ux, uy, vst = self._ux, self._uy, self._vstamp
            for v, (x, y) in zip(verts.tolist(), uv.tolist()):
                ux[v] = x
                uy[v] = y
                vst[v] = stamp
            key = np.sort(faces)
            if rounds >= self.rounds or (faces_before is not None
                                         and np.array_equal(key, faces_before)):
                break
            if not self._uncovered(faces, local, uv, blocked, patch):
                break
            faces_before = key
            prev = stamp
        corner_uv = uv[local]
        keep = self._undistorted(faces, local, uv)
        return Paste(patch=int(patch_index), faces=faces[keep], corner_uv=corner_uv[keep],
                     directions=dirs[keep], seed_point=seed_point, rounds=rounds)

    def _uncovered(self, faces, local, uv, blocked, patch) -> bool:
        """Whether a growable boundary edge of the optimized map meets the hull."""
        FF = self.adj.face_neighbors[faces]
        inside = np.zeros(self.F.shape[0], dtype=bool)
        inside[faces] = True
        nb_ok = (FF >= 0)
        nb_in = np.zeros_like(nb_ok)
        nb_in[nb_ok] = inside[FF[nb_ok]]
        open_side = nb_ok & ~nb_in
        if blocked:
            bl = np.zeros(self.F.shape[0], dtype=bool)
            bl[list(blocked)] = True
            open_side[nb_ok] &= ~bl[FF[nb_ok]]
        if not open_side.any():
            return False
        rows, sides = np.nonzero(open_side)
        a = local[rows, sides]
        b = local[rows, (sides + 1) % 3]
        c = patch.center
        inner = c + (1.0 - REGROW_MARGIN) * (patch.hull - c)
        return bool(segments_meet_polygon(uv[a], uv[b], inner).any())

    def _undistorted(self, faces, local, uv) -> np.ndarray:
        """Indices of the seed's edge-connected part of the faces with a sound map."""
        verts = np.unique(self.F[faces])
        P = self.V[verts]
        J, _ = face_jacobians(P, local, uv)
        s1, s2, det = singular_values(J)
        good = (det > 0) & (s1 <= self.max_stretch * s2)
        if not good[0] or np.count_nonzero(good) < 0.5 * faces.shape[0]:
            # a paste over a field singularity: keep its distortion (the paper
            # covers such places early and over them later), drop only folds
            good = det > 0
        good[0] = True
        if good.all():
            return np.arange(faces.shape[0])
        k = faces.shape[0]
        pos = np.full(self.F.shape[0], -1, dtype=np.int64)
        pos[faces] = np.arange(k)
        FF = self.adj.face_neighbors[faces]
        nb = np.where(FF >= 0, pos[np.maximum(FF, 0)], -1)
        rows = np.repeat(np.arange(k), 3)
        cols = nb.ravel()
        ok = (cols >= 0) & good[rows] & good[np.maximum(cols, 0)]
        g = coo_matrix((np.ones(int(ok.sum()), np.int8), (rows[ok], cols[ok])), shape=(k, k))
        _, comp = connected_components(g, directed=False)
        return np.flatnonzero(good & (comp == comp[0]))
