"""Putting one element of a placed exemplar copy into the texture.

:func:`place_element` decides what happens to an element of the copy: added
when it touches nothing, merged (:func:`geotex.quilting.merge.merge_elements`)
when it touches exactly one element of the texture and corresponds to it,
dropped otherwise (several partners, a collision, leaving the domain).
:func:`touching` is the contact test (shared volume or crossing surfaces),
:func:`clipped_to` the exact-boolean clip of an element to the domain.
"""

from __future__ import annotations

import igl
import numpy as np

from geotex.mesh.geometry import signed_volume
from geotex.mesh.primitives import box
from geotex.mesh.solid import arrays_of_manifold, manifold_of
from geotex.quilting.elements import Element, closed_element_ok, split_elements
from geotex.quilting.merge import merge_elements

__all__ = ["PlacementStats", "place_element", "touching", "coincides", "clipped_to",
           "inside_domain"]


def touching(e: Element, p: Element) -> bool:
    """True when two closed elements share volume, touch, or their surfaces cross.

    A vertex of one inside the other (winding number), a vertex of ``p`` on
    the surface of ``e`` (so exact copies count), else an edge of one piercing
    a face of the other (AABB segment queries); only the parts inside the
    overlap of the two bounding boxes are tested.
    """
    lo = np.maximum(e.lo, p.lo)
    hi = np.minimum(e.hi, p.hi)
    if (lo > hi).any():
        return False
    inside_p = (p.V >= lo).all(axis=1) & (p.V <= hi).all(axis=1)
    inside_e = (e.V >= lo).all(axis=1) & (e.V <= hi).all(axis=1)
    if inside_p.any() and (igl.winding_number(e.V, e.F, p.V[inside_p]) > 0.5).any():
        return True
    if inside_e.any() and (igl.winding_number(p.V, p.F, e.V[inside_e]) > 0.5).any():
        return True
    if inside_p.any():
        # vertices on the other surface: coincident copies (winding number 1/2)
        # and contacts count as touching
        tol = 1e-7 * float(np.linalg.norm(np.maximum(e.hi, p.hi) - np.minimum(e.lo, p.lo)))
        if (e.closest.query(p.V[inside_p])[0] <= tol * tol).any():
            return True
    return _edges_pierce(e, p, lo, hi) or _edges_pierce(p, e, lo, hi)


def _edges_pierce(a: Element, b: Element, lo, hi) -> bool:
    """True when an edge of ``a`` (touching the box ``lo, hi``) crosses a face of ``b``."""
    E = np.r_[a.F[:, [0, 1]], a.F[:, [1, 2]], a.F[:, [2, 0]]]
    E = E[E[:, 0] < E[:, 1]]
    P, Q = a.V[E[:, 0]], a.V[E[:, 1]]
    near = ((np.maximum(P, Q) >= lo).all(axis=1) & (np.minimum(P, Q) <= hi).all(axis=1))
    if not near.any():
        return False
    return bool((b.closest.first_hits(P[near], Q[near] - P[near], max_t=1.0) >= 0).any())


def coincides(e: Element, p: Element, *, tol: float = 0.02) -> bool:
    """True when ``p`` is (nearly) a copy of ``e`` in place.

    Both bounding boxes agree within ``tol`` of ``p``'s footprint (the mean
    of its x and y extents) and the RMS distance of ``p``'s vertices to
    ``e``'s surface is below ``tol`` of it: half the tolerance at which
    :func:`~geotex.quilting.merge.merge_elements` calls aligned copies the
    same element.
    """
    foot = float(np.mean(p.hi[:2] - p.lo[:2])) or 1.0
    if np.abs(e.lo - p.lo).max() > tol * foot or np.abs(e.hi - p.hi).max() > tol * foot:
        return False
    return float(np.sqrt(e.closest.query(p.V)[0].mean())) < tol * foot


class PlacementStats:
    """Counters of the placement loop (reported in :class:`QuiltReport`)."""

    def __init__(self):
        self.merges = {"stitched": 0, "union": 0, "separate": 0, "absorbed": 0, "dropped": 0}
        self.dropped = {"domain": 0, "several_partners": 0, "collision": 0}
        self.seams = []
        self.gap_fills = 0


def inside_domain(p: Element, W: float, H: float) -> bool:
    return bool(p.lo[0] >= 0 and p.lo[1] >= 0 and p.hi[0] <= W and p.hi[1] <= H)


def place_element(p: Element, elements: list, domain, stats: PlacementStats, *,
                  optional: bool = False) -> bool:
    """Add, merge or drop one placed element; True when it was used.

    With ``optional`` (an element of the copy that only reaches into the
    claimed cells) nothing is counted as dropped: the element is added when
    it touches nothing and stays in the domain (a gap fill), merged when it
    touches exactly one element that it corresponds to (the way strands of
    successive copies join into one), and left out otherwise.
    """
    W, H = domain[2], domain[3]
    partners = [k for k, e in enumerate(elements) if touching(e, p)]
    if not partners:
        if p.lo[0] < 0 or p.lo[1] < 0 or p.hi[0] > W or p.hi[1] > H:
            if not optional:
                stats.dropped["domain"] += 1
            return False
        elements.append(p)
        if optional:
            stats.gap_fills += 1
        return True
    if len(partners) > 1:
        if not optional:
            stats.dropped["several_partners"] += 1
        return False
    k = partners[0]
    e = elements[k]
    if coincides(e, p):
        # a copy of an element already there (periodic patterns: most of a copy):
        # nothing to merge, and no alignment shift that could move the element
        stats.merges["absorbed"] += 1
        return True
    r = merge_elements(e.V, e.F, p.V, p.F, fixed_a=e.fixed, domain=domain,
                       corresponding_only=True, cap_a=e.cap)
    if optional and r.status not in ("stitched", "union", "absorbed"):
        return False
    if r.status not in ("separate", "dropped") and _collides(r, elements, k):
        if optional:
            return False
        r = merge_elements(e.V, e.F, p.V, p.F, fixed_a=e.fixed, domain=domain, align=False,
                           corresponding_only=True, cap_a=e.cap)
        if r.status == "separate" or _collides(r, elements, k):
            stats.dropped["collision"] += 1
            return False
    if r.status == "separate":
        # only apart after the alignment shift: the unshifted pair touches
        stats.dropped["collision"] += 1
        return False
    stats.merges[r.status] += 1
    if r.status == "stitched":
        stats.seams.append((r.seam_gap, r.seam_normal_jump))
    if r.status in ("stitched", "union", "absorbed"):
        elements[k] = Element(r.vertices, r.faces, r.fixed, e.prefilled, r.cap)
    return r.status != "dropped"


def clipped_to(p: Element, domain, *, min_fraction: float = 0.2) -> list[Element]:
    """The parts of ``p`` inside the domain (exact boolean), one element per component.

    Parts holding less than ``min_fraction`` of the element's volume are left
    out (slivers along the border look like debris and skew the statistics).
    """
    x0, y0, x1, y1 = domain
    pad = float(p.hi[2] - p.lo[2]) + 1.0
    solid = manifold_of(p.V, p.F) ^ manifold_of(*box((x0, y0, p.lo[2] - pad),
                                                     (x1, y1, p.hi[2] + pad)))
    if solid.is_empty() or solid.status().name != "NoError":
        return []
    V, F = arrays_of_manifold(solid)
    whole = signed_volume(p.V, p.F)
    out = []
    for q in split_elements(V, F):
        if (not closed_element_ok(q.V, q.F, intersections=False)
                and signed_volume(q.V, q.F) >= min_fraction * whole):
            out.append(q)
    return out


def _collides(r, elements, k) -> bool:
    """True when a merge result touches an element other than ``elements[k]``."""
    m = Element(r.vertices, r.faces, r.fixed)
    return any(touching(e, m) for i, e in enumerate(elements) if i != k)
