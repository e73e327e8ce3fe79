"""``chainmail``: European 4-in-1 mail, every ring linked through four neighbours.

Rings lie in rows along x, tilted about the y axis by +-``TILT`` (alternate
rows lean opposite ways, odd rows shifted by half a spacing), so each ring
passes through the two nearest rings of the row above and the two of the row
below.  Spacings ``1.3 R`` within a row and ``1.25 R`` between rows maximise
the smallest distance between ring centre lines (0.487 R); the wire must be
thinner than that distance minus the gap, which :func:`build` checks with the
polygonal centre lines actually meshed.  The lowest side of every ring sinks
to ``z = -depth``.

:func:`diagonal_layout` and :func:`ring_meshes` serve the periodic tile sets
(:mod:`geotex.tiles.periodic`): the same rings with equal spacings
(:data:`DIAGONAL_STEP`), rows along the diagonal of the unit tile, so that the
pattern repeats with period 1 along both tile axes and is its own mirror image
across the tile diagonal.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from geotex.errors import InputError
from geotex.exemplars.builders import assemble, loop_faces
from geotex.exemplars.params import Param

__all__ = ["DESCRIPTION", "PARAMS", "DIAGONAL_STEP", "centre_line_clearance", "period",
           "build", "wire_slack", "diagonal_layout", "ring_meshes"]

DESCRIPTION = "interlocking rings in the European 4-in-1 pattern (rings never touch)"
GAP = 0.01
MARGIN = 0.005
TILT = np.radians(30.0)
ROW_STEP, COL_STEP = 1.25, 1.3              # in units of the ring radius
DIAGONAL_STEP = 1.275      # both spacings of the diagonal layout (clearance 0.480 R)

PARAMS = (
    Param("radius", 0.25, "mean ring radius (row spacing 1.25 radius)", 0.05, 2.0),
    Param("wire", 0.08, "wire diameter (at most about 0.45 radius)", 0.005, 1.0),
    Param("depth", 0.05, "how far the low side of each ring sinks below z = 0", 0.005, 1.0),
    Param("jitter", 0.5, "random ring offset within the free clearance, 0 = regular",
          0.0, 1.0),
    Param("resolution", 16, "segments around each ring (wire: half as many)", 8, 96,
          integer=True),
)


def _frame(sign):
    """Ring plane axes ``u``, ``v`` and normal ``nrm`` for tilt sign +-1, (E, 3) each."""
    s, c = np.sin(TILT), np.cos(TILT)
    sign = np.asarray(sign, float)
    u = np.stack([np.full_like(sign, c), np.zeros_like(sign), -sign * s], -1)
    v = np.broadcast_to(np.array([0.0, 1.0, 0.0]), u.shape)
    nrm = np.stack([sign * s, np.zeros_like(sign), np.full_like(sign, c)], -1)
    return u, v, nrm


def _centre_line(R, sign, k):
    t = 2 * np.pi * np.arange(k) / k
    u, v, _ = _frame(np.array([sign]))
    return R * (np.cos(t)[:, None] * u[0] + np.sin(t)[:, None] * v[0])


def centre_line_clearance(R: float, k: int, steps=(COL_STEP, ROW_STEP)) -> float:
    """Smallest distance between the polygonal centre lines of neighbouring rings.

    ``steps``: spacing within a row and between rows, in units of ``R``.
    """
    a, b = steps[0] * R, steps[1] * R
    A = _centre_line(R, 1, k)
    fine = 4096
    best = np.inf
    for dx, dy, sign in ((a / 2, b, -1), (a, 0, 1), (0, 2 * b, 1), (a, 2 * b, 1),
                         (1.5 * a, b, -1)):
        B = _centre_line(R, sign, k) + np.array([dx, dy, 0.0])
        # sample both polygons densely (points on the segments)
        s = np.linspace(0, 1, fine // k, endpoint=False)[:, None, None]
        PA = (A[None] + s * (np.roll(A, -1, 0) - A)[None]).reshape(-1, 3)
        PB = (B[None] + s * (np.roll(B, -1, 0) - B)[None]).reshape(-1, 3)
        best = min(best, float(cKDTree(PB).query(PA)[0].min()))
    return best


def period(size, p: dict) -> tuple[float, float]:
    """Lattice of the layout: one ring spacing along a row, two row spacings across.

    Rows alternate their tilt, so shifting by one row maps rings onto rings
    tilted the other way; two rows map the pattern onto itself.
    """
    R = p["radius"]
    return (COL_STEP * R, 2 * ROW_STEP * R)


def wire_slack(R: float, wire: float, k: int, steps=(COL_STEP, ROW_STEP),
               what: str = "exemplar 'chainmail'") -> float:
    """Room left between linked rings of radius ``R`` once the wire and :data:`GAP` are in.

    Parameters
    ----------
    R, wire : float
        Ring radius and wire diameter.
    k : int
        Segments around a ring (the tube has ``max(6, k // 2)``).
    steps : tuple of 2 float
        Spacings in units of ``R`` (:func:`centre_line_clearance`).
    what : str
        Name used in the error message.

    Returns
    -------
    float
        Clearance between the polygonal tubes minus :data:`GAP` (non-negative).

    Raises
    ------
    InputError
        The wire is too thick: linked rings would touch.
    """
    rw, m = wire / 2, max(6, k // 2)
    clearance = centre_line_clearance(R, k, steps)
    # the polygonal tube bulges past the true one by at most the inner chord's sagitta
    bulge = (R - rw) * (1 - np.cos(np.pi / k)) + rw * (1 - np.cos(np.pi / m))
    slack = clearance - 2 * rw - GAP - 2 * bulge
    if rw >= 0.5 * R or slack < 0:
        c1, c2 = 1 - np.cos(np.pi / k), 1 - np.cos(np.pi / m)
        rw_max = min((clearance - GAP - 2 * R * c1) / (2 - 2 * c1 + 2 * c2), 0.5 * R)
        raise InputError(f"{what}: wire {wire:g} is too thick for radius "
                         f"{R:g} (linked rings would touch); use wire <= "
                         f"{np.floor(2e4 * max(rw_max, 0)) / 1e4:.4g} or a larger radius")
    return float(slack)


def diagonal_layout(n: int, offset: float, lo: float, hi: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ring centres of the diagonal 4-in-1 layout inside the square ``[lo, hi]^2``.

    Rows run along ``(1, 1)``; both spacings are ``1 / (n sqrt 2)``, so the
    centres are ``offset + (p, q) / (4 n)`` for integers ``p``, ``q`` (exact
    in floating point for ``n`` a power of two), row ``k = (q - p) / 4``
    passes through ``(offset, offset) + k (-1, 1) / (2 n)``, and the layout
    repeats with period 1 along both axes (``n`` even) and is its own mirror
    image across the line ``x = y``.

    Parameters
    ----------
    n : int
        Rings per row in one period along the diagonal; even.
    offset : float
        Shift of the layout along the diagonal.
    lo, hi : float
        Square holding the centres.

    Returns
    -------
    pq : numpy.ndarray, (E, 2) int64
        The integers ``(p, q)``.
    centres : numpy.ndarray, (E, 2) float64
    sign : numpy.ndarray, (E,) float64
        Tilt of every ring, ``+1`` on even rows, ``-1`` on odd ones.

    Raises
    ------
    InputError
        ``n`` not a positive even number.
    """
    if n < 2 or n % 2:
        raise InputError(f"diagonal layout: n must be a positive even number, got {n}")
    d = 4 * n
    p = np.arange(int(np.floor((lo - offset) * d)) - 1, int(np.ceil((hi - offset) * d)) + 2)
    P, Q = np.meshgrid(p, p, indexing="ij")
    P, Q = P.ravel(), Q.ravel()
    k, r = (Q - P) // 4, (P + Q) // 2
    ok = ((Q - P) % 4 == 0) & ((P + Q) % 2 == 0) & ((r - k) % 2 == 0)
    C = offset + np.stack([P, Q], -1) / d
    ok &= ((C >= lo) & (C <= hi)).all(axis=1)
    pq = np.stack([P[ok], Q[ok]], -1)
    return pq, C[ok], np.where(k[ok] % 2 == 0, 1.0, -1.0)


def _diagonal_frame(sign):
    """Ring plane axes for rows along ``(1, 1)``: ``u``, ``v``, ``nrm``, (E, 3) each.

    ``u`` and ``nrm`` have equal x and y components and ``v`` opposite ones,
    bit for bit, so swapping x and y maps every ring onto its mirror image.
    """
    h = np.sqrt(0.5)
    s, c = np.sin(TILT), np.cos(TILT)
    sign = np.asarray(sign, float)
    u = np.stack([np.full_like(sign, c * h), np.full_like(sign, c * h), -sign * s], -1)
    v = np.broadcast_to(np.array([-h, h, 0.0]), u.shape)
    nrm = np.stack([sign * (s * h), sign * (s * h), np.full_like(sign, c)], -1)
    return u, v, nrm


def _tube(centre, u, v, nrm, cos_t, sin_t, R, rw, m):
    """Tube points of rings, (E, k, m, 3): ``k`` stations of ``m`` points each."""
    psi = 2 * np.pi * np.arange(m) / m                                   # (m,)
    radial = cos_t[..., None] * u[:, None] + sin_t[..., None] * v[:, None]   # (E, k, 3)
    return (centre[:, None, None]
            + (R + rw * np.cos(psi))[None, None, :, None] * radial[:, :, None]
            + (rw * np.sin(psi))[None, None, :, None] * nrm[:, None, None])


def _mirror_loop_faces(k: int, m: int) -> np.ndarray:
    """Torus faces (``k`` stations of ``m`` points) split so that station ``i`` <-> ``-i``
    maps the triangulation onto itself: quads of stations ``0 .. k/2 - 1`` are
    split along one diagonal, the others along the other ((2 k m, 3) int64)."""
    ring = np.arange(k * m, dtype=np.int64).reshape(k, m)
    a, b = ring, np.roll(ring, -1, axis=1)
    d, c = np.roll(a, -1, axis=0), np.roll(b, -1, axis=0)
    first = (np.arange(k) < k // 2)[:, None, None]
    t1 = np.where(first, np.stack([a, b, c], -1), np.stack([a, b, d], -1))
    t2 = np.where(first, np.stack([a, c, d], -1), np.stack([b, c, d], -1))
    return np.concatenate([t1.reshape(-1, 3), t2.reshape(-1, 3)])


def ring_meshes(centres: np.ndarray, sign: np.ndarray, *, radius: float, wire: float,
                depth: float, resolution: int) -> tuple[np.ndarray, np.ndarray]:
    """Closed rings of the diagonal layout (:func:`diagonal_layout`) at ``centres``.

    The angle table around every ring is symmetric (``cos`` even, ``sin`` odd
    bit for bit) and so is the triangulation (:func:`_mirror_loop_faces`),
    so rings placed at mirror-image centres across ``x = y`` are mirror
    images of each other bit for bit, vertices and edges, and a ring centred
    on that line is its own. The lowest side of every ring sinks to
    ``z = -depth``.

    Parameters
    ----------
    centres : numpy.ndarray, (E, 2) float64
    sign : numpy.ndarray, (E,) float64
        Tilt of every ring (``+-1``).
    radius, wire, depth : float
        Ring radius, wire diameter, sink depth.
    resolution : int
        Segments around each ring (the wire has ``max(6, resolution // 2)``); even.

    Returns
    -------
    V : numpy.ndarray, (E k m, 3) float64
    F : numpy.ndarray, (2 E k m, 3) int64
        Ring ``e`` owns vertices ``e k m .. (e + 1) k m - 1``; outward oriented.
    """
    k, rw = int(resolution), wire / 2
    if k % 2:
        raise InputError(f"rings of the diagonal layout need an even resolution, got {k}")
    m = max(6, k // 2)
    half = np.arange(k // 2 + 1)
    c, s = np.cos(2 * np.pi * half / k), np.sin(2 * np.pi * half / k)
    s[0] = 0.0
    if k % 2 == 0:
        s[-1] = 0.0
    idx = np.minimum(np.arange(k), k - np.arange(k))
    cos_t = c[idx]
    sin_t = np.where(np.arange(k) <= k // 2, s[idx], -s[idx])
    E = len(centres)
    u, v, nrm = _diagonal_frame(sign)
    zc = radius * np.sin(TILT) + rw - depth
    centre = np.column_stack([np.asarray(centres, float), np.full(E, zc)])
    P = _tube(centre, u, v, nrm, np.broadcast_to(cos_t, (E, k)),
              np.broadcast_to(sin_t, (E, k)), radius, rw, m)
    return assemble(P.reshape(E, k * m, 3), _mirror_loop_faces(k, m))


def build(size, rng: np.random.Generator, p: dict):
    """Return ``(V, F)`` of the rings; see :data:`PARAMS`."""
    R, rw, depth = p["radius"], p["wire"] / 2, p["depth"]
    k = p["resolution"]
    m = max(6, k // 2)
    slack = wire_slack(R, p["wire"], k)
    a, b = COL_STEP * R, ROW_STEP * R
    shift = 0.4 * p["jitter"] * slack                   # largest random ring offset
    ext = np.array([R * np.cos(TILT) + rw, R + rw]) + shift
    lo, hi = ext + MARGIN, np.asarray(size) - ext - MARGIN
    if np.any(hi < lo):
        raise InputError(f"exemplar 'chainmail': a {size[0]:g} x {size[1]:g} patch is too "
                         f"small for rings of radius {R:g}")
    rows = int(np.floor((hi[1] - lo[1]) / b)) + 1
    per_row = int(np.floor((hi[0] - lo[0]) / a)) + 1
    ii, rr = np.meshgrid(np.arange(per_row), np.arange(rows), indexing="ij")
    ii, rr = ii.ravel(), rr.ravel()
    C = lo + np.stack([ii * a + (rr % 2) * a / 2, rr * b], -1)
    keep = C[:, 0] <= hi[0] + 1e-12
    C, rr = C[keep], rr[keep]
    C += 0.5 * ((hi - C.max(axis=0)) - (C.min(axis=0) - lo))
    order = np.lexsort((C[:, 0], rr))
    C, rr = C[order], rr[order]
    E = C.shape[0]
    ang = rng.uniform(0, 2 * np.pi, E)
    C = C + shift * rng.uniform(0, 1, E)[:, None] * np.stack([np.cos(ang), np.sin(ang)], -1)
    spin = rng.uniform(0, 2 * np.pi / k, E)
    sign = np.where(rr % 2 == 0, 1.0, -1.0)
    u, v, nrm = _frame(sign)
    zc = R * np.sin(TILT) + rw - depth
    t = spin[:, None] + 2 * np.pi * np.arange(k)[None] / k             # (E, k)
    centre = np.column_stack([C, np.full(E, zc)])
    P = _tube(centre, u, v, nrm, np.cos(t), np.sin(t), R, rw, m)
    return assemble(P.reshape(E, k * m, 3), loop_faces(k, m))
