"""The pasting loop of lapped textures (Praun, Finkelstein, Hoppe 2000, §3).

Repeat until every face is covered:

* pick a random texture patch and a random uncovered sample of a random
  face (probability proportional to the face's uncovered area; while fewer
  than half of the faces are covered, multiplied by ``1 + priority * p`` with
  ``p`` in ``[0, 1]`` high at strong curvature and near field singularities
  and discontinuities, so hard places are pasted early and covered over
  later, as the paper suggests);
* paste it there (:class:`geotex.image.paste.Paster`: grow, extend,
  field-aligned least squares, re-grow);
* rasterize the paste into the face coverage
  (:class:`geotex.image.coverage.Coverage`).

Each paste covers at least the sample it is centred on (the patch centre is
opaque), so the loop always ends.
"""

from __future__ import annotations

import math
from numbers import Real
from typing import Callable

import numpy as np

from geotex.errors import InputError
from geotex.fields.frames import face_connection, tangent_angles, wrap_angle
from geotex.fields.singularities import singularities
from geotex.image.coverage import Coverage
from geotex.image.paste import Paster
from geotex.image.patches import TexturePatch
from geotex.image.records import LappedTexture
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.geometry import degenerate_faces
from geotex.patches.grow import face_adjacency

__all__ = ["lapped_texture", "default_scale", "placement_priority", "alignment_errors",
           "DEFAULT_SCALE_FRACTION"]

#: Default texture scale: this fraction of the bounding-box diagonal per patch.
DEFAULT_SCALE_FRACTION = 0.15


def default_scale(V) -> float:
    """Default surface size of a texture patch: 15 % of the bounding-box diagonal."""
    V = np.asarray(V, dtype=np.float64)
    return DEFAULT_SCALE_FRACTION * float(np.linalg.norm(V.max(axis=0) - V.min(axis=0)))


def _field_arrays(field, symmetry, m: int):
    """``(up vectors (m, 3) or None, N)`` from the ``field`` argument."""
    if field is None:
        return None, 1
    if hasattr(field, "vectors") and hasattr(field, "symmetry"):
        if symmetry is not None and int(symmetry) != int(field.symmetry):
            raise InputError(f"symmetry={symmetry} disagrees with field.symmetry="
                             f"{field.symmetry}; leave symmetry out for a DirectionField")
        vec, N = np.asarray(field.vectors, dtype=np.float64), int(field.symmetry)
    else:
        vec = np.asarray(field, dtype=np.float64)
        N = 1 if symmetry is None else symmetry
        try:
            N = int(N)
        except (TypeError, ValueError):
            raise InputError(f"symmetry must be 1, 2 or 4, got {symmetry!r}") from None
    if N not in (1, 2, 4):
        raise InputError(f"symmetry must be 1, 2 or 4, got {N}")
    if vec.shape != (m, 3):
        raise InputError(f"field must have one vector per face, shape ({m}, 3), got {vec.shape}")
    if not np.isfinite(vec).all():
        raise InputError("field has non-finite vectors")
    return vec, N


def _scale_array(scale, V, m: int) -> np.ndarray:
    if scale is None:
        return np.full(m, default_scale(V))
    if isinstance(scale, Real) or np.ndim(scale) == 0:
        try:
            s = float(scale)
        except (TypeError, ValueError):
            raise InputError(f"scale must be a positive number, got {scale!r}") from None
        arr = np.full(m, s)
    else:
        arr = np.asarray(scale, dtype=np.float64)
        if arr.shape != (m,):
            raise InputError(f"scale must be a number or one value per face, shape ({m},), "
                             f"got {arr.shape}")
    if not (np.isfinite(arr).all() and (arr > 0).all()):
        raise InputError("scale must be finite and > 0 (surface length of one texture patch)")
    return arr


def placement_priority(V, F, *, up=None, symmetry: int = 1, scale=None,
                       connection=None) -> np.ndarray:
    """Where pasting is hard: ``(m,)`` values in ``[0, 1]``.

    The maximum of three terms: bending, ``min(1, kappa h / (pi / 2))`` with
    ``kappa`` the largest dihedral angle across a face's edges over the dual
    edge length and ``h`` the local scale (a patch bending by a right angle
    scores 1); field discontinuity, the largest turn of the N-direction field
    across an edge after parallel transport over ``pi / (2 N)``; and 1 on
    faces around a field singularity.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    up : array_like, (m, 3), optional
        Direction field (``None``: bending only).
    symmetry : int, optional
    scale : float or array_like (m,), optional
    connection : FaceConnection, optional
        Precomputed :func:`geotex.fields.frames.face_connection`.

    Returns
    -------
    numpy.ndarray, (m,) float64
    """
    V, F = as_mesh_arrays(V, F)
    m = F.shape[0]
    conn = face_connection(V, F) if connection is None else connection
    h = _scale_array(scale, V, m)
    f, g = conn.faces[:, 0], conn.faces[:, 1]
    cosang = np.clip(np.einsum("ij,ij->i", conn.N[f], conn.N[g]), -1.0, 1.0)
    kappa = np.arccos(cosang) / np.maximum(conn.dual_length, 1e-300)
    bend = np.zeros(m)
    np.maximum.at(bend, f, kappa * h[f])
    np.maximum.at(bend, g, kappa * h[g])
    p = np.minimum(1.0, bend / (math.pi / 2.0))
    if up is not None:
        N = int(symmetry)
        th = tangent_angles(conn.T1, conn.T2, up)
        turn = np.abs(wrap_angle(N * (th[g] - th[f] - conn.angle))) / N
        disc = np.zeros(m)
        np.maximum.at(disc, f, turn)
        np.maximum.at(disc, g, turn)
        p = np.maximum(p, np.minimum(1.0, disc / (math.pi / (2.0 * N))))
        sing = np.array([v for v, _ in singularities(V, F, up, symmetry=N)], dtype=np.int64)
        if sing.size:
            near = np.isin(F, sing).any(axis=1)
            p[near] = 1.0
    return p


def lapped_texture(V, F, patches, *, field=None, symmetry: int | None = None, scale=None,
                   seed=None, samples: int = 4, max_normal_angle: float = math.radians(90.0),
                   max_stretch: float = 3.0, rounds: int = 2, priority: float = 4.0,
                   max_pastes: int | None = None,
                   on_paste: Callable[[int, int, int], None] | None = None) -> LappedTexture:
    """Cover a mesh with pasted texture patches (lapped textures).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        A triangle mesh without degenerate faces (any topology; closed or
        open, several components).
    patches : TexturePatch or sequence of TexturePatch
        From :func:`geotex.image.patches.texture_patches`; each paste picks one
        at random.
    field : DirectionField or array_like (m, 3), optional
        Texture "up" direction per face (projected, principal-curvature or
        smooth fields from :mod:`geotex.fields`).  ``None``: isotropic pastes,
        each with a random orientation propagated over its patch.
    symmetry : int, optional
        ``N`` of an array field (1 vectors, 2 lines, 4 crosses); line and
        cross fields are combed locally in each paste.
    scale : float or array_like (m,), optional
        Surface length of one texture unit (the patch's longer side), global
        or per face; default :func:`default_scale`.
    seed : int or numpy.random.Generator, optional
        Same inputs and seed give the same pastes, bit for bit.
    samples : int, optional
        Coverage lattice resolution ``r`` (``r^2`` samples per face).
    max_normal_angle : float, optional
        Normal cone (radians) a surface patch may grow within.
    max_stretch : float, optional
        Faces whose optimized map stretches more (singular-value ratio) are
        left out of their paste.
    rounds : int, optional
        Grow-and-optimize rounds per paste at most.
    priority : float, optional
        Early preference for hard places (see the module docstring); 0 for
        uniform placement.
    max_pastes : int, optional
        Stop after this many pastes (the result is then incomplete).
    on_paste : callable, optional
        ``on_paste(n_pastes, covered_faces, n_faces)`` after every paste
        (progress bars).

    Returns
    -------
    LappedTexture

    Raises
    ------
    InputError
        On malformed or empty meshes, degenerate faces, bad options, no
        texture patch, or a scale below the mean edge length.

    Examples
    --------
    >>> import numpy as np
    >>> from geotex.mesh.primitives import icosphere
    >>> from geotex.image.patches import texture_patches
    >>> V, F = icosphere(2)
    >>> img = np.random.default_rng(0).integers(0, 255, (48, 48, 3), dtype=np.uint8)
    >>> lt = lapped_texture(V, F, texture_patches(img), scale=1.0, seed=1)
    >>> lt.complete
    True
    """
    V, F = as_mesh_arrays(V, F)
    m = F.shape[0]
    if m == 0:
        raise InputError("F is empty: the mesh has no faces to texture")
    bad = degenerate_faces(V, F)
    if np.any(bad):
        idx = np.flatnonzero(bad) if np.asarray(bad).dtype == bool else np.asarray(bad)
        raise InputError(f"the mesh has {idx.size} degenerate faces (first {int(idx[0])}); "
                         "remove them first (geotex repair)")
    if isinstance(patches, TexturePatch):
        patches = (patches,)
    patches = tuple(patches)
    if not patches or not all(isinstance(p, TexturePatch) for p in patches):
        raise InputError("patches must be one or more TexturePatch (see texture_patches)")
    up, N = _field_arrays(field, symmetry, m)
    h = _scale_array(scale, V, m)
    for name, value, lo in (("max_normal_angle", max_normal_angle, 0.0),
                            ("max_stretch", max_stretch, 1.0), ("priority", priority, 0.0)):
        try:
            x = float(value)
        except (TypeError, ValueError):
            raise InputError(f"{name} must be a number, got {value!r}") from None
        if not (math.isfinite(x) and x >= lo):
            raise InputError(f"{name} must be >= {lo:g}, got {value!r}")
    if not 0 < float(max_normal_angle) <= math.pi:
        raise InputError(f"max_normal_angle must be in (0, pi] radians, got {max_normal_angle!r}")
    if int(rounds) < 1 or int(rounds) != rounds:
        raise InputError(f"rounds must be an integer >= 1, got {rounds!r}")
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)

    edge = float(np.mean(np.linalg.norm(V[F] - V[np.roll(F, 1, axis=1)], axis=2)))
    if float(np.median(h)) < edge:
        raise InputError(f"scale {float(np.median(h)):.3g} is smaller than the mean edge length "
                         f"{edge:.3g}: a texture patch would cover less than a face; use a "
                         "larger scale or refine the mesh")
    conn = face_connection(V, F)
    if up is not None:
        up = up - np.einsum("ij,ij->i", up, conn.N)[:, None] * conn.N
        ln = np.linalg.norm(up, axis=1)
        weak = ~(ln > 1e-9)
        if weak.any():
            raise InputError(f"field is zero or normal to the surface on {int(weak.sum())} "
                             f"faces (first {int(np.flatnonzero(weak)[0])}); fill it first "
                             "(e.g. projected_direction_field fills such faces)")
        up = up / ln[:, None]
    adj = face_adjacency(V, F)
    prio = placement_priority(V, F, up=up, symmetry=N, scale=h, connection=conn)
    cov = Coverage(m, resolution=samples)
    K = cov.n_samples
    limit = m * K if max_pastes is None else int(max_pastes)
    if limit < 1:
        raise InputError(f"max_pastes must be >= 1, got {max_pastes!r}")
    paster = Paster(V, F, adj, (conn.T1, conn.T2, conn.N), up=up, symmetry=N, scale=h,
                    max_normal_angle=float(max_normal_angle), max_stretch=float(max_stretch),
                    rounds=int(rounds), max_faces=m)
    area = adj.areas
    boost = 1.0 + float(priority) * prio
    pastes = []
    while len(pastes) < limit:
        unc = K - cov.count
        if not unc.any():
            break
        early = np.count_nonzero(unc == 0) < 0.5 * m
        w = area * unc * (boost if early else 1.0)
        cdf = np.cumsum(w)
        f = int(np.searchsorted(cdf, rng.random() * cdf[-1], side="right"))
        f = min(f, m - 1)
        if unc[f] == 0:                                   # round-off at a zero-weight face
            f = int(np.flatnonzero(unc)[0])
        free = np.flatnonzero(~cov.covered[f])
        s = int(free[rng.integers(free.size)])
        k = int(rng.integers(len(patches)))
        paste = paster.paste(f, cov.bary[s], patches[k], k, rng)
        cov.update(paste.faces, paste.corner_uv, patches[k])
        cov.mark(f, s)
        pastes.append(paste)
        if on_paste is not None:
            on_paste(len(pastes), int(np.count_nonzero(cov.covered_faces)), m)
    meta = {"scale": float(h[0]) if np.all(h == h[0]) else "per-face",
            "field": "isotropic" if up is None else f"{N}-direction",
            "symmetry": int(N), "samples": int(samples), "n_pastes": len(pastes),
            "max_normal_angle": float(max_normal_angle), "max_stretch": float(max_stretch),
            "rounds": int(rounds), "priority": float(priority)}
    if isinstance(seed, (int, np.integer)):
        meta["seed"] = int(seed)
    return LappedTexture(pastes=tuple(pastes), patches=patches, n_vertices=V.shape[0],
                         n_faces=m, coverage=cov.fraction(), metadata=meta)


def alignment_errors(V, F, lapped: LappedTexture) -> np.ndarray:
    """Angle between each pasted face's mapped "up" direction and the texture's +v axis.

    For every face of every paste, the Jacobian ``J`` of its texture map is
    applied to the direction the paste aligned to (``Paste.directions``);
    the error is the angle between ``J d`` and ``(0, 1)``.  Zero means the
    texture's up follows the field exactly there.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    lapped : LappedTexture

    Returns
    -------
    numpy.ndarray, (t,) float64
        Radians in ``[0, pi]``, stacked like :meth:`LappedTexture.layers`.
    """
    V, F = as_mesh_arrays(V, F)
    face, _, _, uv = lapped.layers()
    if face.size == 0:
        return np.zeros(0)
    dirs = np.concatenate([p.directions for p in lapped.pastes])
    P = V[F[face]]
    e1 = P[:, 1] - P[:, 0]
    e1 /= np.linalg.norm(e1, axis=1)[:, None]
    n = np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0])
    n /= np.linalg.norm(n, axis=1)[:, None]
    e2 = np.cross(n, e1)
    # Jacobian in the frame (e1, e2): solve [q1 q2] = J [p1 p2]
    p1 = np.stack([np.einsum("ij,ij->i", P[:, 1] - P[:, 0], e1),
                   np.einsum("ij,ij->i", P[:, 1] - P[:, 0], e2)], axis=1)
    p2 = np.stack([np.einsum("ij,ij->i", P[:, 2] - P[:, 0], e1),
                   np.einsum("ij,ij->i", P[:, 2] - P[:, 0], e2)], axis=1)
    Pm = np.stack([p1, p2], axis=2)                        # (t, 2, 2) columns
    Qm = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], axis=2)
    J = Qm @ np.linalg.inv(Pm)
    d2 = np.stack([np.einsum("ij,ij->i", dirs, e1), np.einsum("ij,ij->i", dirs, e2)], axis=1)
    Jd = np.einsum("tij,tj->ti", J, d2)
    return np.abs(np.arctan2(Jd[:, 0], Jd[:, 1]))
