"""A planar height-and-tilt texture put on any base through field-aligned charts.

The source is a texture over a *flat* base in the XY plane (normals +z), for
example :func:`geotex.heighttilt.procedural.bumpy_plane` with
``periodic=True``.  Its texture space is the XY plane itself, and the source
rectangle (the XY bounding box of the base) is one period: a point ``(x, y)``
reads the texture at ``origin + ((x, y) - origin) mod period``.  The wrap is
seamless only when opposite borders of the source carry the same heights and
leans, which ``bumpy_plane(periodic=True)`` guarantees (and
``periodic=False`` nearly does: its bumps stay off the border, so the border
is flat with zero lean).

:func:`transfer_planar` then

1. **refines** the target so that its edges are about as long as the
   source's mean edge times ``scale`` (texture detail needs vertices):
   isotropic remeshing (pymeshlab, reprojected on the input surface) or
   midpoint subdivision;
2. **covers** it with disc patches (:func:`geotex.patches.grow_patch`, radius
   ``patch_radius``, normal cone 75 degrees, field within 45 degrees of the
   seed's so that charts stay small where the field turns quickly, as near
   its singularities), seeded in random order at faces farther than
   ``CORE = 0.65`` radius from every earlier seed;
3. **parameterizes** every patch with
   :func:`geotex.param.field_aligned_parameterization` at ``scale`` (one
   texture unit spans ``scale`` on the surface; ``u`` follows the field,
   ``v = n x u``).  Each new patch is translated in texture space, modulo the
   period, by the circular mean of its offset to the charts already placed
   on the vertices they share, so neighbouring charts agree where they
   overlap (up to the field's curvature) and seams stay faint;
4. **blends**: a vertex belongs to the patch whose centre is nearest in
   that patch's own texture coordinates; within ``blend * scale`` of the
   seam with the second-nearest patch the two charts are mixed with a
   smoothstep weight (0.5 / 0.5 on the seam);
5. **resamples** heights barycentrically in the source (``igl`` closest
   point on the flat source) and multiplies them by ``scale`` (texture
   lengths scale with the texture); the **tilt 1-form** is the pull-back of
   the source tilt: every target edge is mapped into texture space through
   the charts of its end points and the source tilt is integrated along the
   mapped segment with ``samples`` Gauss points, times ``scale`` (so lean
   angles are kept).  At the vertices the carried tilt is ``scale * J^T t``
   with ``J`` the chart's per-vertex Jacobian (mean of the incident face
   gradients of ``u`` and ``v``); a per-vertex residual makes the decoded
   tilt equal to it, as in :func:`geotex.heighttilt.transfer.transfer_texture`.

The textured target is ``apply_texture(result.vertices, result.faces,
result.texture)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from geotex.errors import InputError
from geotex.heighttilt._kernels import dot, edge_encode
from geotex.heighttilt.base import base_geometry, decode_on, frames_of
from geotex.heighttilt.reconstruct import texture_base
from geotex.heighttilt.refine import refine_base, refine_field
from geotex.heighttilt.texture import HeightTiltTexture
from geotex.heighttilt.transfer import _project
from geotex.param.local import field_aligned_parameterization, gradient_operator
from geotex.patches.grow import face_adjacency, grow_patch
from geotex.progress import report
from geotex.options import positive_number

__all__ = ["PlanarTransfer", "transfer_planar", "planar_source"]

#: Seeds keep this fraction of the patch radius from earlier seeds; the rest is overlap
#: (for the translation matching and the seam blend).
CORE = 0.65
#: Normal-cone half angle of the patches (degrees): keeps charts low-distortion.
PATCH_NORMAL_ANGLE = 75.0
#: Largest angle (degrees) between a patch face's field vector and the seed's.
MAX_FIELD_TURN = 45.0


@dataclass(frozen=True, eq=False)
class PlanarTransfer:
    """Result of :func:`transfer_planar`.

    Attributes
    ----------
    vertices : numpy.ndarray, (n, 3) float64
        The refined target base.
    faces : numpy.ndarray, (m, 3) int64
    texture : HeightTiltTexture
        Over ``faces``.
    uv : numpy.ndarray, (n, 2) float64
        Texture coordinates of every vertex in its own patch (source units,
        not wrapped).
    owner : numpy.ndarray, (n,) int64
        Patch of every vertex.
    field : numpy.ndarray, (m, 3) float64
        The direction field used, per refined face.
    n_patches : int
    """

    vertices: np.ndarray
    faces: np.ndarray
    texture: HeightTiltTexture
    uv: np.ndarray
    owner: np.ndarray
    field: np.ndarray
    n_patches: int


@dataclass(frozen=True)
class _Source:
    V: np.ndarray
    F: np.ndarray
    height: np.ndarray
    tilt: np.ndarray            # (n, 2) decoded source tilt (x, y)
    origin: np.ndarray
    period: np.ndarray
    spacing: float
    z: float

    def sample(self, uv: np.ndarray, what: str = "both"):
        """Heights and/or 2-D tilts at texture points ``uv`` (wrapped into the period)."""
        xy = self.origin + np.mod(uv - self.origin, self.period)
        P = np.column_stack([xy, np.full(xy.shape[0], self.z)])
        f, B = _project(P, self.V, self.F)
        T = self.F[f]
        t = np.einsum("pk,pkd->pd", B, self.tilt[T]) if what != "height" else None
        h = np.einsum("pk,pk->p", B, self.height[T]) if what != "tilt" else None
        return h, t


def planar_source(Vs, F, tex) -> _Source:
    """Validate a planar source texture; return its sampler.

    Raises
    ------
    InputError
        The texture does not belong to ``(Vs, F)``, or the base is not flat in
        the XY plane with normals +z.
    """
    g = texture_base(Vs, F, tex)
    lo, hi = g.V.min(axis=0), g.V.max(axis=0)
    ext = hi - lo
    diag = float(np.linalg.norm(ext[:2]))
    if not (ext[0] > 0 and ext[1] > 0) or ext[2] > 1e-9 * diag:
        raise InputError("the source base must be flat in the XY plane (constant z) with a "
                         f"non-empty rectangle; its extent is {ext.tolist()}")
    if (g.normals[:, 2] <= 0).any():
        raise InputError("the source base must face +z (counter-clockwise seen from above); "
                         "flip its faces")
    E = g.topo.edges
    spacing = float(np.linalg.norm(g.V[E[:, 1]] - g.V[E[:, 0]], axis=1).mean())
    t = decode_on(g, tex.tilt, tex.residual)
    return _Source(V=g.V, F=g.F, height=tex.height, tilt=np.ascontiguousarray(t[:, :2]),
                   origin=lo[:2].copy(), period=ext[:2].copy(), spacing=spacing, z=float(lo[2]))


def _cover(V, F, field, radius, start_face, rng):
    """Disc patches around seeds farther than ``CORE * radius`` from earlier seeds.

    A patch takes only faces whose field is within ``MAX_FIELD_TURN`` of the
    seed's (compared in space), so charts stay small where the field turns
    quickly (near its singularities) and their distortion low.
    """
    m = F.shape[0]
    adj = face_adjacency(V, F)
    unit = field / np.linalg.norm(field, axis=1, keepdims=True)
    cos_turn = math.cos(math.radians(MAX_FIELD_TURN))
    order = rng.permutation(m)
    if start_face is not None:
        order = np.concatenate([[start_face], order[order != start_face]])
    covered = np.zeros(m, dtype=bool)
    patches = []
    for f in order.tolist():
        if covered[f]:
            continue
        ref = unit[f]
        p = grow_patch(V, F, f, max_radius=radius,
                       max_normal_angle=math.radians(PATCH_NORMAL_ANGLE),
                       accept=lambda ids, ref=ref: unit[ids] @ ref >= cos_turn, adjacency=adj)
        covered[p.faces[p.distances <= CORE * radius]] = True
        covered[f] = True
        patches.append(p)
    return patches


def _circular_offset(diff, period):
    ang = 2.0 * np.pi * diff / period
    mean = np.arctan2(np.sin(ang).mean(axis=0), np.cos(ang).mean(axis=0))
    return mean * period / (2.0 * np.pi)


def _charts(V, F, field, patches, scale, period, start_uv):
    """Field-aligned chart of every patch, translated to agree with earlier charts."""
    n = V.shape[0]
    have = np.zeros(n, dtype=bool)                 # vertex already in a chart
    best = np.full(n, np.inf)                      # distance to that chart's centre
    best_uv = np.zeros((n, 2))                     # and its texture coordinates
    rows_p, rows_v, rows_uv, rows_d, rows_gu, rows_gv = [], [], [], [], [], []
    for k, p in enumerate(patches):
        uv, verts = field_aligned_parameterization(V, F, p.faces, field, scale=scale,
                                                   center_face=int(p.faces[0]),
                                                   center_uv=(0.0, 0.0))
        shared = have[verts]
        if k == 0:
            offset = np.asarray(start_uv, dtype=np.float64)
        elif shared.any():
            offset = _circular_offset(best_uv[verts[shared]] - uv[shared], period)
        else:
            offset = np.zeros(2)
        uv = uv + offset
        Fl = np.searchsorted(verts, F[p.faces])
        G, _ = gradient_operator(V[verts], Fl)
        gu = (G @ uv[:, 0]).reshape(-1, 3)
        gv = (G @ uv[:, 1]).reshape(-1, 3)
        cnt = np.bincount(Fl.ravel(), minlength=verts.size)
        gu_v = np.column_stack([np.bincount(Fl.ravel(), weights=np.repeat(gu[:, d], 3),
                                            minlength=verts.size) for d in range(3)]) / cnt[:, None]
        gv_v = np.column_stack([np.bincount(Fl.ravel(), weights=np.repeat(gv[:, d], 3),
                                            minlength=verts.size) for d in range(3)]) / cnt[:, None]
        d = scale * np.linalg.norm(uv - offset, axis=1)
        rows_p.append(np.full(verts.size, k))
        rows_v.append(verts)
        rows_uv.append(uv)
        rows_d.append(d)
        rows_gu.append(gu_v)
        rows_gv.append(gv_v)
        better = d < best[verts]
        best[verts[better]] = d[better]
        best_uv[verts[better]] = uv[better]
        have[verts] = True
    cat = np.concatenate
    return (cat(rows_p), cat(rows_v), cat(rows_uv), cat(rows_d), cat(rows_gu), cat(rows_gv))


def _smoothstep(x):
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def transfer_planar(Vs_src, F_src, tex: HeightTiltTexture, V_dst, F_dst, *, scale,
                    field="up", up=(0.0, 0.0, 1.0), refine: str = "remesh",
                    patch_radius=None, blend: float = 0.25, samples: int = 5, seed=0,
                    start_face=None, start_uv=(0.0, 0.0), progress=None) -> PlanarTransfer:
    """Put a planar height-and-tilt texture on a base through field-aligned charts.

    See the module docstring for the method.

    Parameters
    ----------
    Vs_src : array_like, (n_src, 3) float64
        Flat source base in the XY plane, faces counter-clockwise seen from +z.
    F_src : array_like, (m_src, 3) int64
        Must equal ``tex.faces``.
    tex : HeightTiltTexture
        The planar texture; its XY bounding box is one period.
    V_dst : array_like, (n, 3) float64
        Target base (closed or not; no zero-area faces, manifold edges).
    F_dst : array_like, (m, 3) int64
    scale : float
        Surface length of one source unit (> 0): a unit-square source tile
        covers ``scale x scale`` on the target.  Heights are multiplied by it.
    field : {"up", "smooth"} or array_like (m, 3), optional
        Direction the texture's +x axis follows: ``"up"`` the projection of
        ``up`` (lapped textures' default; filled smoothly where ``up`` is
        normal to the surface), ``"smooth"`` the smoothest vector field
        (:func:`geotex.fields.smooth_direction_field`), or one vector per
        face of ``F_dst`` (carried to the refined faces by closest point).
    up : array_like (3,), optional
        Direction for ``field="up"``.
    refine : {"remesh", "subdivide", "none"}, optional
        How the target is brought to edges of about ``scale`` times the
        source's mean edge (see :func:`geotex.heighttilt.refine.refine_base`).
    patch_radius : float, optional
        Patch radius on the surface (default ``1.5 * scale``).
    blend : float, optional
        Width of the seam blend, in units of ``scale`` (0 disables blending).
    samples : int, optional
        Gauss points per edge for the tilt integrals (default 5).
    seed : int, optional
        Order of the patch seeds.
    start_face : int, optional
        First seed face (of the refined mesh); its centroid maps to ``start_uv``.
    start_uv : array_like (2,), optional
    progress : callable, optional
        ``progress(stage)`` at each of 6 stages.

    Returns
    -------
    PlanarTransfer

    Raises
    ------
    InputError
        Bad source (not flat, not +z, texture of another mesh), bad target,
        non-positive ``scale``, ``patch_radius`` or ``samples``, negative
        ``blend``, unknown ``field`` or ``refine``, a field of the wrong shape.
    """
    scale = positive_number(scale, name="scale")
    radius = (1.5 * scale if patch_radius is None
              else positive_number(patch_radius, name="patch_radius"))
    try:
        blend = float(blend)
    except (TypeError, ValueError):
        raise InputError(f"blend must be a non-negative number, got {blend!r}") from None
    if not (math.isfinite(blend) and blend >= 0):
        raise InputError(f"blend must be a non-negative number, got {blend!r}")
    if (isinstance(samples, (bool, np.bool_)) or not isinstance(samples, (int, np.integer))
            or samples < 1):
        raise InputError(f"samples must be an integer >= 1, got {samples!r}")
    cuv = np.asarray(start_uv, dtype=np.float64)
    if cuv.shape != (2,) or not np.isfinite(cuv).all():
        raise InputError(f"start_uv must be two finite numbers, got {start_uv!r}")
    report(progress, "source")
    src = planar_source(Vs_src, F_src, tex)
    gd = base_geometry(V_dst, F_dst, name="V_dst")
    report(progress, "refine")
    Vr, Fr = refine_base(gd.V, gd.F, src.spacing * scale, method=refine)
    g = base_geometry(Vr, Fr, name="refined target")
    if start_face is not None:
        try:
            start_face = int(start_face)
        except (TypeError, ValueError):
            raise InputError(f"start_face must be a face index, got {start_face!r}") from None
        if not 0 <= start_face < Fr.shape[0]:
            raise InputError(f"start_face must be in [0, {Fr.shape[0]}), got {start_face}")
    fld = refine_field(gd.V, gd.F, Vr, Fr, field, up=up)
    report(progress, "patches")
    rng = np.random.default_rng(seed)
    patches = _cover(Vr, Fr, fld, radius, start_face, rng)
    report(progress, "charts")
    pid, vid, uv, dist, gu, gv = _charts(Vr, Fr, fld, patches, scale, src.period, cuv)
    report(progress, "resample")
    tex_out, uv_v, owner = _resample(g, src, pid, vid, uv, dist, gu, gv, scale,
                                     blend * scale, int(samples))
    meta = dict(tex_out.metadata, scale=scale, patches=len(patches), refine=refine,
                field=field if isinstance(field, str) else "array")
    report(progress, "done")
    out = HeightTiltTexture._trusted(tex_out.height, tex_out.tilt, Fr, tex_out.residual, meta,
                                     topology=g.topo)
    return PlanarTransfer(vertices=Vr, faces=Fr, texture=out, uv=uv_v, owner=owner,
                          field=fld, n_patches=len(patches))


def _resample(g, src, pid, vid, uv, dist, gu, gv, scale, band, samples):
    n = g.V.shape[0]
    order = np.lexsort((dist, vid))
    pid, vid, uv, dist, gu, gv = (a[order] for a in (pid, vid, uv, dist, gu, gv))
    first = np.flatnonzero(np.r_[True, vid[1:] != vid[:-1]])
    if first.size != n:
        raise InputError("the patches do not cover every target vertex; "
                         "use a larger patch_radius")
    nxt = first + 1
    has2 = np.zeros(n, dtype=bool)
    ok = nxt < vid.size
    has2[ok] = vid[nxt[ok]] == vid[first[ok]]
    second = np.where(has2, nxt, first)
    d1, d2 = dist[first], np.where(has2, dist[second], np.inf)
    if band > 0:
        w1 = 0.5 + 0.5 * _smoothstep((d2 - d1) / band)
    else:
        w1 = np.ones(n)
    w2 = 1.0 - w1
    rows = np.concatenate([first, second])
    h_all, t_all = src.sample(uv[rows])
    height = scale * (w1 * h_all[:n] + w2 * h_all[n:])
    carried = scale * (t_all[:, :1] * gu[rows] + t_all[:, 1:] * gv[rows])
    tv = g.tangent(w1[:, None] * carried[:n] + w2[:, None] * carried[n:])
    # edges: the charts of both end points that hold the whole edge
    E = g.topo.edges
    key_sorted = pid * n + vid
    srt = np.argsort(key_sorted, kind="stable")
    keys = key_sorted[srt]

    def row_of(p, v):
        k = p * n + v
        i = np.minimum(np.searchsorted(keys, k), keys.size - 1)
        return np.where(keys[i] == k, srt[i], -1)

    cand_p = np.stack([pid[first[E[:, 0]]], pid[second[E[:, 0]]],
                       pid[first[E[:, 1]]], pid[second[E[:, 1]]]], axis=1)

    def vertex_weight(v, p):
        return (np.where(pid[first[v]] == p, w1[v], 0.0)
                + np.where(has2[v] & (pid[second[v]] == p), w2[v], 0.0))

    qs, qw = np.polynomial.legendre.leggauss(samples)
    qs, qw = 0.5 * (qs + 1.0), 0.5 * qw
    num = np.zeros(E.shape[0])
    den = np.zeros(E.shape[0])
    for k in range(4):
        p = cand_p[:, k]
        dup = np.zeros(E.shape[0], dtype=bool)
        for j in range(k):
            dup |= cand_p[:, j] == p
        ri, rj = row_of(p, E[:, 0]), row_of(p, E[:, 1])
        W = 0.5 * (vertex_weight(E[:, 0], p) + vertex_weight(E[:, 1], p))
        use = np.flatnonzero(~dup & (ri >= 0) & (rj >= 0) & (W > 0))
        if use.size == 0:
            continue
        a, b = uv[ri[use]], uv[rj[use]]
        pts = a[:, None, :] + qs[None, :, None] * (b - a)[:, None, :]
        _, t = src.sample(pts.reshape(-1, 2), what="tilt")
        c = scale * np.einsum("q,eqd,ed->e", qw, t.reshape(use.size, samples, 2), b - a)
        num[use] += W[use] * c
        den[use] += W[use]
    c = edge_encode(g.V, E, tv)              # fallback where no chart holds an edge
    has = den > 0
    c[has] = num[has] / den[has]
    u = decode_on(g, c)
    _, T1, T2 = frames_of(g, u)
    miss = tv - u
    r = np.stack([dot(miss, T1), dot(miss, T2)], axis=1)
    out = HeightTiltTexture._trusted(height, c, g.F, r, {"source": "transfer_planar",
                                                         "samples": samples,
                                                         "fallback_edges": int((~has).sum())})
    return out, uv[first], pid[first]
