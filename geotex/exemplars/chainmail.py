"""``chainmail``: European 4-in-1 mail, every ring linked through four neighbours.

Rings lie in rows along x, tilted about the y axis by +-``TILT`` (alternate
rows lean opposite ways, odd rows shifted by half a spacing), so each ring
passes through the two nearest rings of the row above and the two of the row
below.  Spacings ``1.3 R`` within a row and ``1.25 R`` between rows maximise
the smallest distance between ring centre lines (0.487 R); the wire must be
thinner than that distance minus the gap, which :func:`build` checks with the
polygonal centre lines actually meshed.  The lowest side of every ring sinks
to ``z = -depth``.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from geotex.errors import InputError
from geotex.exemplars.builders import assemble, loop_faces
from geotex.exemplars.params import Param

__all__ = ["DESCRIPTION", "PARAMS", "centre_line_clearance", "period", "build"]

DESCRIPTION = "interlocking rings in the European 4-in-1 pattern (rings never touch)"
GAP = 0.01
MARGIN = 0.005
TILT = np.radians(30.0)
ROW_STEP, COL_STEP = 1.25, 1.3              # in units of the ring radius

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


def centre_line_clearance(R: float, k: int) -> float:
    """Smallest distance between the polygonal centre lines of neighbouring rings."""
    a, b = COL_STEP * R, ROW_STEP * R
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


def build(size, rng: np.random.Generator, p: dict):
    """Return ``(V, F)`` of the rings; see :data:`PARAMS`."""
    R, rw, depth = p["radius"], p["wire"] / 2, p["depth"]
    k = p["resolution"]
    m = max(6, k // 2)
    clearance = centre_line_clearance(R, k)
    # the polygonal tube bulges past the true one by at most the inner chord's sagitta
    bulge = (R - rw) * (1 - np.cos(np.pi / k)) + rw * (1 - np.cos(np.pi / m))
    slack = clearance - 2 * rw - GAP - 2 * bulge
    if rw >= 0.5 * R or slack < 0:
        c1, c2 = 1 - np.cos(np.pi / k), 1 - np.cos(np.pi / m)
        rw_max = min((clearance - GAP - 2 * R * c1) / (2 - 2 * c1 + 2 * c2), 0.5 * R)
        raise InputError(f"exemplar 'chainmail': wire {p['wire']:g} is too thick for radius "
                         f"{R:g} (linked rings would touch); use wire <= "
                         f"{np.floor(2e4 * max(rw_max, 0)) / 1e4:.4g} or a larger radius")
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
    psi = 2 * np.pi * np.arange(m) / m                                   # (m,)
    radial = (np.cos(t)[..., None] * u[:, None] + np.sin(t)[..., None] * v[:, None])  # (E,k,3)
    centre = np.column_stack([C, np.full(E, zc)])
    P = (centre[:, None, None]
         + (R + rw * np.cos(psi))[None, None, :, None] * radial[:, :, None]
         + (rw * np.sin(psi))[None, None, :, None] * nrm[:, None, None])
    return assemble(P.reshape(E, k * m, 3), loop_faces(k, m))
