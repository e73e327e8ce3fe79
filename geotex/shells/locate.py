"""Map tile points on polycube quads onto the base and into the shell.

A tile point ``(u, v, w)`` on quad ``q`` (``u, v`` in ``[0, 1]``, see
:mod:`geotex.param.polycube_quads` for the quad frame) lies in a face of the
quad's triangle sub-grid (:meth:`geotex.param.polycube.PolyCube.locate`); its
barycentric coordinates there give the base point ``x = sum b_i Y_i`` on the
fitted surface and the offset direction ``d = normalize(sum b_i D_i)``; the
shell point is ``x + w * height * d``.
"""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.jit import JIT_MIN_SIZE, compiled

__all__ = ["locate_on_quads", "quad_points_to_base", "quad_points_to_shell"]


def _args(shell, quad_ids, uv):
    q = np.asarray(quad_ids)
    if q.ndim != 1 or q.dtype.kind not in "iu":
        raise InputError("quad_ids must be a 1-D integer array")
    q = q.astype(np.int64)
    UV = np.asarray(uv, dtype=np.float64)
    if UV.shape != (q.size, 2):
        raise InputError(f"uv must have shape ({q.size}, 2), got {UV.shape}")
    if q.size and (q.min() < 0 or q.max() >= shell.n_quads):
        raise InputError(f"quad_ids must lie in [0, {shell.n_quads})")
    if not np.isfinite(UV).all():
        raise InputError("uv has non-finite values")
    return q, UV


def locate_on_quads(shell, quad_ids, uv) -> tuple[np.ndarray, np.ndarray]:
    """Face of the fitted surface and barycentric coordinates of quad points.

    Parameters
    ----------
    shell : Shell
    quad_ids : array_like, (k,) int
    uv : array_like, (k, 2) float64
        Tile coordinates in ``[0, 1]`` (clamped).

    Returns
    -------
    face : (k,) int64
        Faces of ``shell.polycube.F``.
    bary : (k, 3) float64
        Non-negative, summing to 1.

    Raises
    ------
    InputError
        On malformed arguments or quad ids out of range.
    """
    q, UV = _args(shell, quad_ids, uv)
    return shell.polycube.locate(q, UV)


def interpolated(values: np.ndarray, F: np.ndarray, face: np.ndarray, bary: np.ndarray
                 ) -> np.ndarray:
    """``sum_i bary_i values[F[face, i]]``, ``(k, d)``.

    From :data:`geotex.jit.JIT_MIN_SIZE` barycentric coordinates up a compiled
    loop without temporaries gives the same values bit for bit.
    """
    if (bary.size >= JIT_MIN_SIZE and values.ndim == 2 and bary.ndim == 2
            and values.dtype == bary.dtype == np.float64):
        out = np.empty((face.shape[0], values.shape[1]))
        _interpolated_loops(np.ascontiguousarray(values), np.ascontiguousarray(F, np.int64),
                            np.ascontiguousarray(face, np.int64), np.ascontiguousarray(bary),
                            out)
        return out
    c = F[face]
    return (bary[:, 0:1] * values[c[:, 0]] + bary[:, 1:2] * values[c[:, 1]]
            + bary[:, 2:3] * values[c[:, 2]])


@compiled
def _interpolated_loops(values, F, face, bary, out):
    """Compiled :func:`interpolated` into ``out``: the same three products and two sums."""
    for k in range(face.shape[0]):
        f = face[k]
        i0, i1, i2 = F[f, 0], F[f, 1], F[f, 2]
        b0, b1, b2 = bary[k, 0], bary[k, 1], bary[k, 2]
        for j in range(values.shape[1]):
            out[k, j] = b0 * values[i0, j] + b1 * values[i1, j] + b2 * values[i2, j]


def quad_points_to_base(shell, quad_ids, uv) -> tuple[np.ndarray, np.ndarray]:
    """Base points and unit offset directions of quad points, each ``(k, 3)``."""
    face, bary = locate_on_quads(shell, quad_ids, uv)
    pc = shell.polycube
    x = interpolated(pc.Y, pc.F, face, bary)
    d = interpolated(shell.D, pc.F, face, bary)
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    return x, d


def quad_points_to_shell(shell, quad_ids, uvw, *, height: float) -> np.ndarray:
    """Shell points ``x + w * height * d`` of tile points ``(u, v, w)``, ``(k, 3)``.

    Raises
    ------
    InputError
        If ``height`` is not in ``(0, shell.max_height]`` or ``uvw`` is malformed.
    """
    P = np.asarray(uvw, dtype=np.float64)
    if P.ndim != 2 or P.shape[1] != 3:
        raise InputError(f"uvw must have shape (k, 3), got {P.shape}")
    if not (0 < float(height) <= shell.max_height * (1 + 1e-12)):
        raise InputError(f"height {height} must lie in (0, {shell.max_height:.4g}] "
                         "(the shell's max_height)")
    x, d = quad_points_to_base(shell, quad_ids, P[:, :2])
    return x + (P[:, 2:3] * float(height)) * d
