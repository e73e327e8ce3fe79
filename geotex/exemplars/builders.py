"""Small vectorized generators of closed element meshes.

Every element is a *ring stack*: ``k`` rings of ``n`` points each, either
closed by a pole at both ends (surfaces of revolution, star-shaped solids over
a plan outline, swept strands with end caps) or joined end to end (tori).  One
face template serves every element of a kind; copies are concatenated with
index offsets by :func:`assemble`, which also orients each copy outward.
"""

from __future__ import annotations

import numpy as np

__all__ = ["stack_faces", "loop_faces", "stack_vertices", "assemble",
           "smooth_noise", "noise_at", "polygon_outline"]


def _bands(rings: np.ndarray, closed: bool) -> np.ndarray:
    """Triangles between consecutive rows of ``rings`` ((k, n) vertex indices)."""
    nxt = np.roll(rings, -1, axis=1)
    a, b = rings[:-1], nxt[:-1]
    d, c = rings[1:], nxt[1:]
    if closed:
        a = np.concatenate([a, rings[-1:]])
        b = np.concatenate([b, nxt[-1:]])
        d = np.concatenate([d, rings[:1]])
        c = np.concatenate([c, nxt[:1]])
    return np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3),
                           np.stack([a, c, d], -1).reshape(-1, 3)])


def stack_faces(k: int, n: int) -> np.ndarray:
    """Faces of a closed surface through ``k`` rings of ``n`` points between two poles.

    Vertex order: pole 0, ring 0 (``n`` points), ..., ring ``k - 1``, pole 1.

    Returns
    -------
    numpy.ndarray, (2 n k, 3) int64
        Consistently oriented (outward when the rings turn counter-clockwise
        seen from pole 1; :func:`assemble` fixes the sign anyway).
    """
    rings = 1 + np.arange(k * n, dtype=np.int64).reshape(k, n)
    nxt = np.roll(rings, -1, axis=1)
    top = k * n + 1
    start = np.stack([np.zeros(n, np.int64), nxt[0], rings[0]], -1)
    end = np.stack([np.full(n, top, np.int64), rings[-1], nxt[-1]], -1)
    return np.concatenate([start, _bands(rings, False), end])


def loop_faces(k: int, n: int) -> np.ndarray:
    """Faces of a torus-like surface through ``k`` rings of ``n`` points, ring k-1 joined to 0.

    Returns
    -------
    numpy.ndarray, (2 n k, 3) int64
    """
    return _bands(np.arange(k * n, dtype=np.int64).reshape(k, n), True)


def stack_vertices(rings: np.ndarray, pole0: np.ndarray, pole1: np.ndarray) -> np.ndarray:
    """Vertex array of ring stacks in the order expected by :func:`stack_faces`.

    Parameters
    ----------
    rings : numpy.ndarray, (E, k, n, 3)
    pole0, pole1 : numpy.ndarray, (E, 3)

    Returns
    -------
    numpy.ndarray, (E, k n + 2, 3)
    """
    E = rings.shape[0]
    return np.concatenate([pole0[:, None], rings.reshape(E, -1, 3), pole1[:, None]], axis=1)


def assemble(P: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Concatenate ``E`` copies of one element topology, each oriented outward.

    Parameters
    ----------
    P : numpy.ndarray, (E, nv, 3) float64
        Vertex positions of every copy.
    F : numpy.ndarray, (m, 3) int64
        The shared face template (indices into ``[0, nv)``).

    Returns
    -------
    V : numpy.ndarray, (E nv, 3) float64
    F : numpy.ndarray, (E m, 3) int64
        Copy ``e`` occupies faces ``[e m, (e + 1) m)``; a copy whose signed
        volume is negative with the template gets its faces reversed.
    """
    E, nv = P.shape[0], P.shape[1]
    if E == 0:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    C = P - P.mean(axis=1, keepdims=True)
    tri = C[:, F]                                              # (E, m, 3, 3)
    vol = np.einsum("emk,emk->e", tri[:, :, 0], np.cross(tri[:, :, 1], tri[:, :, 2]))
    FF = np.broadcast_to(F, (E,) + F.shape).copy()
    FF[vol < 0] = FF[vol < 0][:, :, ::-1]
    FF += (np.arange(E, dtype=np.int64) * nv)[:, None, None]
    return np.ascontiguousarray(P.reshape(-1, 3)), np.ascontiguousarray(FF.reshape(-1, 3))


def smooth_noise(rng: np.random.Generator, count: int, *, waves: int = 4,
                 wavelength: float = 1.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Draw ``count`` smooth 1-D noise functions (sums of random sinusoids).

    Returns
    -------
    freq, phase, amp : numpy.ndarray, (count, waves)
        Evaluate with :func:`noise_at`; values stay within ``[-1, 1]``.
    """
    freq = 2 * np.pi / wavelength * rng.uniform(0.5, 2.5, size=(count, waves))
    phase = rng.uniform(0, 2 * np.pi, size=(count, waves))
    amp = rng.uniform(0.3, 1.0, size=(count, waves))
    amp /= amp.sum(axis=1, keepdims=True)
    return freq, phase, amp


def noise_at(noise, rows: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Evaluate noise functions ``rows`` (broadcast against ``t``) at positions ``t``."""
    freq, phase, amp = (a[rows] for a in noise)
    return np.sum(amp * np.sin(freq * t[..., None] + phase), axis=-1)


def polygon_outline(sides: int, per_side: int, *, rotation: float = 0.0) -> np.ndarray:
    """Unit-circumradius regular polygon boundary, each side split in ``per_side`` pieces.

    Returns
    -------
    numpy.ndarray, (sides * per_side, 2) float64
        Counter-clockwise.
    """
    ang = rotation + 2 * np.pi * np.arange(sides) / sides
    corners = np.stack([np.cos(ang), np.sin(ang)], -1)
    t = np.arange(per_side) / per_side
    nxt = np.roll(corners, -1, axis=0)
    pts = corners[:, None] * (1 - t)[None, :, None] + nxt[:, None] * t[None, :, None]
    return pts.reshape(-1, 2)

