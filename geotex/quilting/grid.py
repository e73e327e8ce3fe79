"""The cell grid of the quilting loop: lattice of translations, claims, occupancy.

:class:`CellGrid` answers which free cells a copy at ``t`` claims, which cell
an element belongs to (its footprint centre) and how many of a copy's
elements would collide with the texture; :func:`lattice` lists the cell
multiples a copy may be placed at; :func:`under` tells which points lie under
an element (its projection), for occupancy from prefilled geometry.
"""

from __future__ import annotations

import numpy as np

from geotex.quilting.elements import Element
from geotex.quilting.placement import touching

__all__ = ["CellGrid", "lattice", "under"]


class CellGrid:
    """Cell bookkeeping of the loop: claims and predicted collisions of a copy."""

    def __init__(self, CX, CY, cw, ch, size, occ, reach, ex_elements):
        self.CX, self.CY, self.cw, self.ch = CX, CY, cw, ch
        self.size, self.occ, self.reach = size, occ, reach
        self.ex = ex_elements
        self.nx, self.ny = occ.shape

    def claim(self, t, si, sj) -> np.ndarray:
        """Free cells inside the copy's box and within ``reach`` of the seed."""
        CX, CY, cw, ch, size = self.CX, self.CY, self.cw, self.ch, self.size
        inside = ((CX - 0.5 * cw >= t[0] - 1e-9) & (CX + 0.5 * cw <= t[0] + size[0] + 1e-9)
                  & (CY - 0.5 * ch >= t[1] - 1e-9) & (CY + 0.5 * ch <= t[1] + size[1] + 1e-9))
        claim = inside & ~self.occ
        if self.reach is not None:
            claim &= ((np.abs(np.arange(self.nx) - si)[:, None] <= self.reach)
                      & (np.abs(np.arange(self.ny) - sj)[None, :] <= self.reach))
        claim[si, sj] = True
        return claim

    def cell_of(self, p: Element) -> tuple[int, int]:
        c = 0.5 * (p.lo[:2] + p.hi[:2])
        return int(np.floor(c[0] / self.cw)), int(np.floor(c[1] / self.ch))

    def collisions(self, t, si, sj, elements) -> int:
        """Elements of the copy at ``t`` centred in its claim that touch the texture."""
        claim = self.claim(t, si, sj)
        hits = 0
        for ex in self.ex:
            lo, hi = ex.lo + t, ex.hi + t
            ci = int(np.floor(0.5 * (lo[0] + hi[0]) / self.cw))
            cj = int(np.floor(0.5 * (lo[1] + hi[1]) / self.ch))
            if not (0 <= ci < self.nx and 0 <= cj < self.ny and claim[ci, cj]):
                continue
            near = [e for e in elements if (e.lo <= hi).all() and (e.hi >= lo).all()]
            if near:
                p = Element(ex.V + t, ex.F, ex.fixed)
                hits += any(touching(e, p) for e in near)
        return hits


def under(e: Element, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Which points ``(x, y)`` lie under the element (in its projection on the plane)."""
    T = e.V[e.F][:, :, :2]
    a, b, c = T[:, 0], T[:, 1], T[:, 2]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    keep = np.abs(det) > 1e-14 * float(np.ptp(e.V[:, :2], axis=0).max() or 1.0) ** 2
    a, b, c, det = a[keep], b[keep], c[keep], det[keep]
    px = x[:, None] - a[None, :, 0]
    py = y[:, None] - a[None, :, 1]
    u = (px * (c[None, :, 1] - a[None, :, 1]) - py * (c[None, :, 0] - a[None, :, 0])) / det
    v = (py * (b[None, :, 0] - a[None, :, 0]) - px * (b[None, :, 1] - a[None, :, 1])) / det
    return ((u >= 0) & (v >= 0) & (u + v <= 1)).any(axis=1)


def lattice(lo: float, hi: float, length: float, cell: float) -> np.ndarray:
    """Multiples ``m * cell`` with ``m * cell <= lo`` and ``m * cell + length >= hi``.

    Copies are placed on one global lattice of spacing ``cell`` (the exemplar's
    pitch by default), so neighbouring copies keep the pattern's phase even
    when the grid cells were stretched to fit the output size.
    """
    eps = 1e-9 * cell
    m0 = int(np.ceil((hi - length - eps) / cell))
    m1 = int(np.floor((lo + eps) / cell))
    return np.arange(m0, m1 + 1, dtype=np.float64) * cell
