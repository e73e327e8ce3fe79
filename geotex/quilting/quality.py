"""The quality report of a quilted texture.

Everything a caller needs to trust (or reject) a synthesized texture: every
element closed and manifold, no interpenetration between elements, how the
element statistics compare with the exemplar's, how well the merged seams
close, how often the exact-boolean fallback was needed, and timings.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field

import igl
import numpy as np

from geotex.check.intersections import self_intersecting_pairs
from geotex.mesh.topology import compacted, edge_topology, face_components
from geotex.quilting.elements import closed_element_ok

__all__ = ["QuiltReport", "quilt_report", "element_stats", "coverage_fraction", "nested_pairs"]


@dataclass
class QuiltReport:
    """Quality figures of a quilted texture (all plain numbers; JSON friendly).

    Attributes
    ----------
    elements : int
        Closed components in the output.
    prefilled_elements : int
        Of which came from the caller's ``prefilled`` geometry.
    bad_elements : int
        Elements that are not closed, edge/vertex-manifold, consistently and
        outward oriented solids (must be 0).  Prefilled elements cut open by
        a domain side are checked with their openings capped.
    self_intersecting_elements : int
        Elements that intersect themselves.
    intersecting_element_pairs : int
        Pairs of distinct (unmerged) elements whose surfaces intersect.
    nested_element_pairs : int
        Pairs of distinct elements of which one lies inside the other without
        the surfaces crossing (a vertex of one has winding number above 1/2
        with respect to the other).
    placements : int
        Exemplar copies placed.
    gap_fills : int
        Elements added because they reach into a claim and touch nothing.
    merges : dict
        Outcome counts of element merges: ``stitched`` (graph cut + stitch),
        ``union`` (manifold3d fallback), ``separate``, ``absorbed``,
        ``dropped``.
    fallback_unions : int
        ``merges["union"]``.
    dropped : dict
        Placed elements not used: ``domain`` (would leave the domain with no
        partner), ``several_partners`` (touching more than one element),
        ``collision`` (the merged element would touch a third element).
    seam_gap_mean, seam_gap_max : float
        Loop-to-loop distance bridged by the stitch strips, relative to the
        cell size.
    seam_normal_jump_mean, seam_normal_jump_max : float
        Angle (degrees) between the faces on either side of the seams.
    footprint_mean, footprint_std, height_mean, height_std : float
        Element footprint (mean of the bounding box's x and y extents) and
        height (top ``z``) in the output.
    exemplar_footprint_mean, exemplar_footprint_std, exemplar_height_mean,
    exemplar_height_std : float
        The same in the exemplar.
    coverage, exemplar_coverage : float
        Fraction of the domain (of the exemplar's rectangle) under an element.
    icp_iterations : int
    cells : list of int
        Grid size ``[nx, ny]``.
    cell : list of float
        Cell size ``[cw, ch]``.
    timings : dict
        Seconds per stage (``match``, ``merge``, ``synthesis``, ``report``).
    """

    elements: int = 0
    prefilled_elements: int = 0
    bad_elements: int = 0
    self_intersecting_elements: int = 0
    intersecting_element_pairs: int = 0
    nested_element_pairs: int = 0
    placements: int = 0
    gap_fills: int = 0
    merges: dict = field(default_factory=dict)
    fallback_unions: int = 0
    dropped: dict = field(default_factory=dict)
    seam_gap_mean: float = float("nan")
    seam_gap_max: float = float("nan")
    seam_normal_jump_mean: float = float("nan")
    seam_normal_jump_max: float = float("nan")
    footprint_mean: float = float("nan")
    footprint_std: float = float("nan")
    height_mean: float = float("nan")
    height_std: float = float("nan")
    exemplar_footprint_mean: float = float("nan")
    exemplar_footprint_std: float = float("nan")
    exemplar_height_mean: float = float("nan")
    exemplar_height_std: float = float("nan")
    coverage: float = float("nan")
    exemplar_coverage: float = float("nan")
    icp_iterations: int = 0
    cells: list = field(default_factory=list)
    cell: list = field(default_factory=list)
    timings: dict = field(default_factory=dict)

    @property
    def valid(self) -> bool:
        """True when every element is a valid solid and no two elements intersect or nest."""
        return (self.bad_elements == 0 and self.self_intersecting_elements == 0
                and self.intersecting_element_pairs == 0 and self.nested_element_pairs == 0)

    def to_dict(self) -> dict:
        """Plain dict (``nan`` becomes ``None``)."""
        def clean(x):
            if isinstance(x, float) and not np.isfinite(x):
                return None
            if isinstance(x, dict):
                return {k: clean(v) for k, v in x.items()}
            if isinstance(x, list):
                return [clean(v) for v in x]
            return x
        return clean(asdict(self))

    def to_json(self, **kwargs) -> str:
        """JSON text of :meth:`to_dict`."""
        return json.dumps(self.to_dict(), **kwargs)

    def summary(self) -> str:
        """One line: validity, counts, statistics against the exemplar, time."""
        m = self.merges
        return (f"{self.elements} elements ({'valid' if self.valid else 'INVALID'}: "
                f"{self.bad_elements} bad, {self.intersecting_element_pairs} intersecting "
                f"and {self.nested_element_pairs} nested pairs), "
                f"{self.placements} placements, merges {m.get('stitched', 0)} stitched / "
                f"{self.fallback_unions} union fallback, "
                f"{sum(self.dropped.values()) + m.get('dropped', 0)} copies' elements "
                f"dropped; coverage {self.coverage:.0%} "
                f"(exemplar {self.exemplar_coverage:.0%}), footprint {self.footprint_mean:.3g} "
                f"(exemplar {self.exemplar_footprint_mean:.3g}), height {self.height_mean:.3g} "
                f"(exemplar {self.exemplar_height_mean:.3g}); "
                f"{self.timings.get('synthesis', float('nan')):.2f} s")


def element_stats(V: np.ndarray, F: np.ndarray, element_ids: np.ndarray) -> dict:
    """Footprint (mean of x and y extents) and height (top z) per element: mean and std."""
    if F.shape[0] == 0:
        return {"footprint_mean": float("nan"), "footprint_std": float("nan"),
                "height_mean": float("nan"), "height_std": float("nan")}
    k = int(element_ids.max()) + 1
    lo = np.full((k, 3), np.inf)
    hi = np.full((k, 3), -np.inf)
    T = V[F]
    for c in range(3):
        Pc = T[:, :, c]
        np.minimum.at(lo[:, c], element_ids, Pc.min(axis=1))
        np.maximum.at(hi[:, c], element_ids, Pc.max(axis=1))
    foot = 0.5 * ((hi[:, 0] - lo[:, 0]) + (hi[:, 1] - lo[:, 1]))
    top = hi[:, 2]
    return {"footprint_mean": float(foot.mean()), "footprint_std": float(foot.std()),
            "height_mean": float(top.mean()), "height_std": float(top.std())}


def nested_pairs(V: np.ndarray, F: np.ndarray, element_ids: np.ndarray) -> np.ndarray:
    """Pairs ``(a, b)`` of elements where ``a`` lies inside ``b`` (one vertex tested).

    Only pairs whose bounding boxes contain each other's tested vertex are
    examined, and only closed elements ``b`` (a Wang tile's frame halves are
    open along the sides); a vertex of ``a`` with winding number above 1/2
    with respect to ``b`` means ``a`` starts inside ``b`` (elements whose
    surfaces cross are counted by the intersection test instead).

    Returns
    -------
    numpy.ndarray, (p, 2) int64
    """
    k = int(element_ids.max()) + 1 if element_ids.size else 0
    if k < 2:
        return np.zeros((0, 2), np.int64)
    order = np.argsort(element_ids, kind="stable")
    bounds = np.searchsorted(element_ids[order], np.arange(k + 1))
    faces = [F[order[bounds[e]:bounds[e + 1]]] for e in range(k)]
    probe = np.array([V[f[0, 0]] for f in faces])
    lo = np.array([V[f].reshape(-1, 3).min(axis=0) for f in faces])
    hi = np.array([V[f].reshape(-1, 3).max(axis=0) for f in faces])
    inside_box = ((probe[:, None] >= lo[None]) & (probe[:, None] <= hi[None])).all(axis=2)
    np.fill_diagonal(inside_box, False)
    out = []
    closed = {}
    for a, b in zip(*np.nonzero(inside_box)):
        if b not in closed:          # open elements (frame halves cut by a side) are skipped
            closed[b] = edge_topology(faces[b], V.shape[0]).boundary.size == 0
        if closed[b] and igl.winding_number(V, faces[b], probe[a:a + 1])[0] > 0.5:
            out.append((int(a), int(b)))
    return np.array(out, dtype=np.int64).reshape(-1, 2)


def coverage_fraction(V: np.ndarray, F: np.ndarray, rect, *, resolution: int = 200) -> float:
    """Fraction of ``rect = (x0, y0, x1, y1)`` covered by the projection of upward faces.

    Sampled on a regular grid of about ``resolution`` points along the longer side.
    """
    x0, y0, x1, y1 = (float(r) for r in rect)
    step = max(x1 - x0, y1 - y0) / resolution
    xs = np.arange(x0 + 0.5 * step, x1, step)
    ys = np.arange(y0 + 0.5 * step, y1, step)
    if xs.size == 0 or ys.size == 0 or F.shape[0] == 0:
        return 0.0
    covered = np.zeros((xs.size, ys.size), dtype=bool)
    T = V[F][:, :, :2]
    e1 = T[:, 1] - T[:, 0]
    e2 = T[:, 2] - T[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    up = np.flatnonzero(det > 1e-15 * max(step, 1e-300) ** 2)
    lo = T[up].min(axis=1)
    hi = T[up].max(axis=1)
    # rasterise triangle by triangle in blocks (each covers few samples)
    i0 = np.clip(np.ceil((lo[:, 0] - xs[0]) / step), 0, xs.size).astype(np.int64)
    i1 = np.clip(np.floor((hi[:, 0] - xs[0]) / step) + 1, 0, xs.size).astype(np.int64)
    j0 = np.clip(np.ceil((lo[:, 1] - ys[0]) / step), 0, ys.size).astype(np.int64)
    j1 = np.clip(np.floor((hi[:, 1] - ys[0]) / step) + 1, 0, ys.size).astype(np.int64)
    ni, nj = i1 - i0, j1 - j0
    cnt = np.maximum(ni, 0) * np.maximum(nj, 0)
    has = cnt > 0
    up, i0, j0, ni, nj, cnt = up[has], i0[has], j0[has], ni[has], nj[has], cnt[has]
    if up.size == 0:
        return 0.0
    tri = np.repeat(np.arange(up.size), cnt)
    local = np.arange(cnt.sum()) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    ii = i0[tri] + local // nj[tri]
    jj = j0[tri] + local % nj[tri]
    f = up[tri]
    px, py = xs[ii] - T[f, 0, 0], ys[jj] - T[f, 0, 1]
    d = det[f]
    a = (px * e2[f, 1] - py * e2[f, 0]) / d
    b = (e1[f, 0] * py - e1[f, 1] * px) / d
    inside = (a >= 0) & (b >= 0) & (a + b <= 1)
    covered[ii[inside], jj[inside]] = True
    return float(covered.mean())


def quilt_report(V, F, element_ids, *, exemplar, domain, merges, dropped, seams, placements,
                 icp_iterations, cells, cell, prefilled=0, gap_fills=0,
                 element_problems=None) -> QuiltReport:
    """Build the :class:`QuiltReport` of a quilted texture (see its attributes).

    ``element_problems`` (one string per element, empty when the element is
    a valid closed solid) replaces the per-element check, e.g. when some
    elements are open on the domain boundary and were checked with their caps.
    """
    rep = QuiltReport()
    k = int(element_ids.max()) + 1 if element_ids.size else 0
    rep.elements = k
    rep.prefilled_elements = int(prefilled)
    if element_problems is not None:
        bad = sum(1 for p in element_problems if p)
    else:
        bad = 0
        order = np.argsort(element_ids, kind="stable")
        bounds = np.searchsorted(element_ids[order], np.arange(k + 1))
        for e in range(k):
            if closed_element_ok(*compacted(V, F[order[bounds[e]:bounds[e + 1]]]),
                                 intersections=False):
                bad += 1
    rep.bad_elements = bad
    pairs = self_intersecting_pairs(V, F) if F.shape[0] else np.zeros((0, 2), np.int64)
    ea, eb = element_ids[pairs[:, 0]], element_ids[pairs[:, 1]]
    rep.self_intersecting_elements = int(np.unique(ea[ea == eb]).size)
    cross = np.unique(np.sort(np.c_[ea, eb][ea != eb], axis=1), axis=0)
    rep.intersecting_element_pairs = int(cross.shape[0])
    nest = nested_pairs(V, F, element_ids)
    if nest.size:                            # crossing pairs are already counted
        crossing = {tuple(x) for x in cross.tolist()}
        nest = [p for p in np.sort(nest, axis=1).tolist() if tuple(p) not in crossing]
    rep.nested_element_pairs = int(len({tuple(p) for p in np.asarray(nest).reshape(-1, 2).tolist()}))
    rep.placements = int(placements)
    rep.gap_fills = int(gap_fills)
    rep.merges = {k2: int(v) for k2, v in merges.items()}
    rep.fallback_unions = int(merges.get("union", 0))
    rep.dropped = {k2: int(v) for k2, v in dropped.items()}
    scale = float(np.mean(cell))
    if seams:
        S = np.asarray(seams, dtype=np.float64)
        g, j = S[:, 0] / scale, S[:, 1]
        rep.seam_gap_mean, rep.seam_gap_max = float(np.nanmean(g)), float(np.nanmax(g))
        if np.isfinite(j).any():
            rep.seam_normal_jump_mean = float(np.nanmean(j))
            rep.seam_normal_jump_max = float(np.nanmax(j))
    for key, val in element_stats(V, F, element_ids).items():
        setattr(rep, key, val)
    VE, FE, size = exemplar
    _, lab = face_components(FE, VE.shape[0])
    for key, val in element_stats(VE, FE, lab).items():
        setattr(rep, "exemplar_" + key, val)
    rep.coverage = coverage_fraction(V, F, domain)
    rep.exemplar_coverage = coverage_fraction(VE, FE, (0.0, 0.0, size[0], size[1]))
    rep.icp_iterations = int(icp_iterations)
    rep.cells = [int(c) for c in cells]
    rep.cell = [float(c) for c in cell]
    return rep
