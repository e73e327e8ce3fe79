"""Constrained mesh quilting: fill a rectangle with copies of an exemplar texture.

The plane is cut into cells about one element pitch wide (one period of the
exemplar's layout when it reports one, e.g. chain mail).  Cells
are *occupied* when the caller says so (``occupied`` rectangles, or the
centre lies under a ``prefilled`` element) or once an exemplar copy has
covered them.  Until every cell of the output domain ``[0, W] x [0, H]`` is occupied:

1. **Seed**: the free cell with the most occupied neighbours (8-neighbourhood;
   ties broken by the seeded generator).
2. **Match** (:mod:`~geotex.quilting.match`): every translation of the
   exemplar on the lattice of cell multiples (``(m cx, n cy)``, one lattice
   for the whole output) that covers the seed cell (and ``cover`` rings around
   it, when possible) is scored by the matching energy over the texture's
   vertices in the ``window`` rings of cells around the seed, and the best
   few are refined by ICP in the plane.  With nothing to match (first copy)
   the generator picks one.
3. **Claim**: the free cells inside the translated exemplar box and within
   ``reach`` cells of the seed.
4. **Place**: each element of the copy whose footprint centre lies in a
   claimed cell is added as it is when it touches nothing; merged
   (:mod:`~geotex.quilting.merge`: graph cut, weld or pull and stitch) when
   it touches exactly one element of the texture and corresponds to it (an
   ICP-aligned copy of it, possibly overlapping it only in part, like two
   pieces of one strand); dropped when it touches several, collides with an
   element it does not correspond to, or would leave the domain without a
   partner (the merge itself removes any part of it outside the domain).  A
   merge whose result would touch a third element is retried without the
   alignment shift, and dropped if it still does.
   Elements of the copy centred elsewhere that reach into the claim
   (``fill_gaps``) are added when they touch nothing, and merged when they
   touch exactly one element they correspond to: that is how the strands of
   successive copies (weave, bark ridges) join into longer strands.  The
   rest of the copy is unused.
   A claimed cell that lost its element is freed again (at most ``retries``
   times) so that a later copy can fill it.

Constrained mode (used to fill the interior of a Wang tile): pass the tile's
frame as ``prefilled`` and mark in ``fixed`` the vertices that must not move
(e.g. those on the tile edges).  Prefilled elements may be closed (and may
then extend outside the domain), or open *only* where a domain side cut them
(the frame halves of :mod:`geotex.tiles`: boundary loops lying on the lines
``x = 0``, ``x = W``, ``y = 0``, ``y = H``).  Open ones are capped internally
(:func:`~geotex.quilting.elements.capped`), their cut vertices are fixed
automatically, and they come back open along exactly the same cut.  Their
cells count as occupied; fixed vertices are returned bit-exact (eliminated
from every Laplacian solve, the faces around them always kept by the cut);
``occupied`` rectangles mark more of the plane as filled (e.g. the frame
strips themselves).  Typical call::

    res = quilt_texture(exemplar, out_size=(1.0, 1.0), prefilled=(Vf, Ff),
                        fixed=on_tile_edge, occupied=strip_rectangles, seed=tile_seed)
    V, F = res.vertices, res.faces   # frame (merged with copies) + interior
    # res.fixed marks the fixed vertices (positions bit-exact),
    # res.element_prefilled the frame's elements, res.report.valid the checks
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import igl
import numpy as np

from geotex.errors import InputError
from geotex.mesh.arrays import as_mesh_arrays
from geotex.progress import report as report_progress
from geotex.quilting.elements import (Element, capped, closed_element_ok,
                                      concatenate_elements, split_elements, texture_arrays)
from geotex.quilting.grid import CellGrid, lattice, under
from geotex.quilting.match import ExemplarIndex, best_translation
from geotex.quilting.placement import PlacementStats, clipped_to, place_element
from geotex.quilting.quality import QuiltReport, quilt_report

__all__ = ["QuiltResult", "quilt_texture", "default_cell"]


@dataclass
class QuiltResult:
    """Output of :func:`quilt_texture`.

    Attributes
    ----------
    vertices : numpy.ndarray, (n, 3) float64
    faces : numpy.ndarray, (m, 3) int64
        All elements (prefilled ones first, in their order), each a closed
        outward-oriented component.
    element_ids : numpy.ndarray, (m,) int64
        Element of every face, ``0 .. elements - 1``.
    fixed : numpy.ndarray, (n,) bool
        Output vertices that are fixed input vertices (positions bit-exact).
    report : QuiltReport
    element_prefilled : numpy.ndarray, (elements,) bool
        True for elements that come from ``prefilled`` (possibly merged with
        copies); they are the first ones.
    """

    vertices: np.ndarray
    faces: np.ndarray
    element_ids: np.ndarray
    fixed: np.ndarray
    report: QuiltReport
    element_prefilled: np.ndarray = None


def default_cell(elements: list[Element], size, params=None, period=None):
    """About one element pitch: the grid cell and the lattice of copy translations.

    In order of preference: the exemplar's ``period`` (``(px, py)``: the
    translations that map its pattern onto itself, which procedural
    exemplars with a lattice layout report, e.g. chain mail rows alternate
    their tilt so the period across the rows is two row spacings), its
    ``params["pitch"]`` (procedural exemplars: copies placed at multiples of
    the pitch keep the pattern's phase, which matters for weaves and
    knurls), else ``sqrt(exemplar area / element count)``.

    Returns
    -------
    float or tuple (cx, cy)
    """
    if period is not None:
        try:
            px, py = (float(c) for c in period)
        except (TypeError, ValueError):
            px = py = float("nan")
        if np.isfinite([px, py]).all() and 0 < px <= size[0] and 0 < py <= size[1]:
            return (px, py)
    pitch = (params or {}).get("pitch") if isinstance(params, dict) else None
    if pitch is not None:
        try:
            pitch = float(pitch)
        except (TypeError, ValueError):
            pitch = None
    if pitch is not None and np.isfinite(pitch) and 0 < pitch <= min(size):
        return pitch
    return float(np.sqrt(size[0] * size[1] / max(len(elements), 1)))


def _cell_pair(cell) -> tuple[float, float]:
    try:
        c = np.asarray(cell, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        c = np.zeros(0)
    if c.size == 1:
        c = np.r_[c, c]
    if c.size != 2 or not (np.isfinite(c).all() and (c > 0).all()):
        raise InputError(f"cell must be a positive number or a pair (cx, cy), got {cell!r}")
    return float(c[0]), float(c[1])


def _rects(occupied) -> np.ndarray:
    if occupied is None:
        return np.zeros((0, 4))
    R = np.asarray(occupied, dtype=np.float64).reshape(-1, 4) if np.size(occupied) else \
        np.zeros((0, 4))
    if not np.isfinite(R).all() or (R[:, 2] < R[:, 0]).any() or (R[:, 3] < R[:, 1]).any():
        raise InputError("occupied must be (k, 4) rectangles (xmin, ymin, xmax, ymax) "
                         "with xmin <= xmax and ymin <= ymax")
    return R


def quilt_texture(V, F=None, *, size=None, out_size, cell=None, seed=0, prefilled=None,
                  fixed=None, occupied=None, boundary="drop", lam=None, refine=3, window=2,
                  cover=1, reach=2, retries=2, fill_gaps=True, avoid_collisions=True,
                  max_steps=None, progress=None) -> QuiltResult:
    """Synthesize a larger planar geometric texture from an exemplar.

    Parameters
    ----------
    V : array_like (n, 3) float64, or exemplar-like object
        Exemplar vertices, or an object with ``vertices``, ``faces``, ``size``
        (and optionally ``elements()``), such as a
        :class:`geotex.exemplars.Exemplar`.  Its elements are closed
        components standing on ``z = 0`` inside ``[0, lx] x [0, ly]``.
    F : array_like, (m, 3) int64, optional
        Exemplar faces (with array input).
    size : tuple (lx, ly), optional
        Exemplar extent (defaults to the object's ``size``).
    out_size : tuple (W, H)
        Output domain ``[0, W] x [0, H]``.
    cell : float or tuple (cx, cy), optional
        Grid cell size, also the lattice of copy translations; default
        :func:`default_cell` (the exemplar's period or pitch, or about one
        element pitch).  Cells are stretched slightly so the domain holds a whole
        number of them.
    seed : int, optional
        Seed of the random generator (ties, first placement).  Same inputs and
        seed give byte-identical output.
    prefilled : tuple (Vp (k, 3), Fp (l, 3)), or a mesh-like object, optional
        Geometry already in the output (e.g. a Wang tile's frame); kept in the
        output, its elements are merged with corresponding copies.  Each
        element is closed, or open only along cuts on the domain sides (see
        the module docstring).
    fixed : array_like of int or (k,) bool, optional
        Vertices of ``prefilled`` that must not move (bit-exact in the output).
    occupied : array_like, (r, 4), optional
        Rectangles ``(xmin, ymin, xmax, ymax)`` that count as filled: cells
        whose centre lies in one are never quilted.
    boundary : {"drop", "clip"}, optional
        What happens to a placed element that would cross the domain
        boundary and has no partner inside: ``"drop"`` it (elements stay
        whole), or ``"clip"`` it to the domain with an exact boolean
        intersection (a flat cut face on the boundary; better coverage for
        long elements such as strands).
    lam : float, optional
        Distance weight of the matching energy (default ``1 / cell``, the
        mean of the two sides for a pair).
    refine : int, optional
        Best candidates refined by ICP at each step.
    window : int, optional
        Rings of cells around the seed whose texture is matched.
    cover : int, optional
        Rings of cells around the seed that the placed copy must cover
        (reduced automatically when the exemplar is too small).
    reach : int or None, optional
        A copy claims only free cells at most this many cells (Chebyshev
        distance) from the seed, where it was matched; ``None`` claims every
        free cell under the copy (fewer, larger steps, more collisions).
    retries : int, optional
        A claimed cell whose element had to be dropped is freed again, at
        most this many times, so that a later copy can fill it.
    avoid_collisions : bool, optional
        When the best match would put elements onto elements of the texture,
        take the finalist (refined or not) whose copy collides least.
    fill_gaps : bool, optional
        Also use elements of the copy that are centred outside the claim but
        reach into it: added when they touch nothing (fills the gaps that
        long elements leave), merged when they touch exactly one element
        they correspond to (joins strands).
    max_steps : int, optional
        Stop after this many placements (default: ``(retries + 1)`` times
        the number of cells).
    progress : callable, optional
        Called at each placement with ``"placement K: FILLED/TOTAL cells"``
        (the cells occupied before it; the command line draws its bar from
        these counts).

    Returns
    -------
    QuiltResult

    Raises
    ------
    InputError
        On malformed arrays or options, a cell larger than the exemplar, an
        exemplar element that is not a closed solid, or a prefilled element
        that is not one (open away from the domain sides).

    Examples
    --------
    >>> import numpy as np
    >>> from geotex.mesh.primitives import icosphere
    >>> V, F = icosphere(1)
    >>> V = V * [0.2, 0.2, 0.1] + [0.5, 0.5, 0.0]
    >>> r = quilt_texture(V, F, size=(1, 1), out_size=(2, 1), cell=0.5)
    >>> r.report.bad_elements
    0
    """
    t_start = time.perf_counter()
    VE, FE, size, ids = texture_arrays(V, F, size)
    try:
        W, H = (float(s) for s in out_size)
    except (TypeError, ValueError):
        raise InputError(f"out_size must be two numbers (W, H), got {out_size!r}") from None
    if not (W > 0 and H > 0 and np.isfinite([W, H]).all()):
        raise InputError(f"out_size must be positive, got {out_size!r}")
    ex_elements = split_elements(VE, FE, element_ids=ids)
    for i, e in enumerate(ex_elements):
        problem = closed_element_ok(e.V, e.F, intersections=False)
        if problem:
            raise InputError(f"exemplar element {i} (around "
                             f"{e.V.mean(axis=0).round(3).tolist()}) is not a closed solid: {problem}; repair the "
                             "exemplar (geotex repair) first")
    if cell is None:
        cell = default_cell(ex_elements, size, getattr(V, "params", None),
                            getattr(V, "period", None))
    pitch_x, pitch_y = _cell_pair(cell)
    if boundary not in ("drop", "clip"):
        raise InputError(f"boundary must be 'drop' or 'clip', got {boundary!r}")
    if int(window) < 0 or int(cover) < 0:
        raise InputError(f"window and cover must be >= 0, got {window}, {cover}")
    nx, ny = max(1, int(round(W / pitch_x))), max(1, int(round(H / pitch_y)))
    cw, ch = W / nx, H / ny
    window, cover = int(window), int(cover)
    while cover > 0 and ((2 * cover + 1) * cw > size[0] or (2 * cover + 1) * ch > size[1]):
        cover -= 1
    if cw > size[0] or ch > size[1]:
        raise InputError(f"cell {cell!r} is larger than the exemplar {size}; "
                         "give a smaller cell or a larger exemplar")
    lam = 2.0 / (pitch_x + pitch_y) if lam is None else float(lam)
    rng = np.random.default_rng(seed)
    domain = (0.0, 0.0, W, H)

    elements: list[Element] = []
    if prefilled is not None:
        if hasattr(prefilled, "vertices"):
            Vp, Fp = prefilled.vertices, prefilled.faces
        else:
            try:
                Vp, Fp = prefilled
            except (TypeError, ValueError):
                raise InputError("prefilled must be a pair (V, F) or a mesh") from None
        Vp, Fp = as_mesh_arrays(Vp, Fp, allow_empty=False)
        elements = [_closed(e, (0.0, 0.0, W, H))
                    for e in split_elements(Vp, Fp, fixed=fixed, prefilled=True)]
        for i, e in enumerate(elements):
            problem = closed_element_ok(e.V, e.F, intersections=False)
            if problem:
                raise InputError(f"prefilled element {i} (around "
                                 f"{e.V.mean(axis=0).round(3).tolist()}) is not a closed "
                                 f"solid even with its cuts capped: {problem}")
    elif fixed is not None:
        raise InputError("fixed vertices need prefilled geometry (fixed indexes prefilled)")

    cx = (np.arange(nx) + 0.5) * cw
    cy = (np.arange(ny) + 0.5) * ch
    CX, CY = np.meshgrid(cx, cy, indexing="ij")
    occ = np.zeros((nx, ny), dtype=bool)
    for r in _rects(occupied):
        occ |= (CX >= r[0]) & (CX <= r[2]) & (CY >= r[1]) & (CY <= r[3])
    for e in elements:
        box = (CX >= e.lo[0]) & (CX <= e.hi[0]) & (CY >= e.lo[1]) & (CY <= e.hi[1])
        if box.any():
            occ[box] |= under(e, CX[box], CY[box])

    index = ExemplarIndex(VE, FE)
    grid = CellGrid(CX, CY, cw, ch, size, occ, reach, ex_elements)
    stats = PlacementStats()
    timing = {"match": 0.0, "merge": 0.0}
    steps = 0
    icp_iterations = 0
    tries = np.zeros((nx, ny), dtype=np.int64)
    limit = (retries + 1) * nx * ny if max_steps is None else int(max_steps)
    while not occ.all() and steps < limit:
        steps += 1
        report_progress(progress, f"placement {steps}: {int(occ.sum())}/{occ.size} cells")
        # (a) seed
        pad = np.pad(occ, 1).astype(np.int64)
        nb = sum(pad[1 + dx:nx + 1 + dx, 1 + dy:ny + 1 + dy]
                 for dx in (-1, 0, 1) for dy in (-1, 0, 1) if dx or dy)
        nb = np.where(occ, -1, nb)
        best = np.flatnonzero(nb.ravel() == nb.max())
        si, sj = np.unravel_index(int(rng.choice(best)), occ.shape)
        # (b) match over cell-multiple translations
        t0 = time.perf_counter()
        for ring in (cover, 0):
            cx0, cy0 = (si - ring) * cw, (sj - ring) * ch
            cx1, cy1 = (si + ring + 1) * cw, (sj + ring + 1) * ch
            tx = lattice(cx0, cx1, size[0], pitch_x)
            ty = lattice(cy0, cy1, size[1], pitch_y)
            if tx.size and ty.size:
                break
        else:  # the stretched grid is off the lattice: cell multiples of the grid
            tx = si * cw - np.arange(int(np.floor(size[0] / cw)) + 1) * cw
            ty = sj * ch - np.arange(int(np.floor(size[1] / ch)) + 1) * ch
            tx = tx[(tx <= cx0 + 1e-9 * cw) & (tx + size[0] >= cx1 - 1e-9 * cw)]
            ty = ty[(ty <= cy0 + 1e-9 * ch) & (ty + size[1] >= cy1 - 1e-9 * ch)]
        TX, TY = np.meshgrid(tx, ty, indexing="ij")
        cand = np.c_[TX.ravel(), TY.ravel(), np.zeros(TX.size)]
        P, N = _window_points(elements, (si - window) * cw, (sj - window) * ch,
                              (si + window + 1) * cw, (sj + window + 1) * ch)
        if P.shape[0] >= 3:
            m = best_translation(P, N, index, cand, lam=lam, refine=refine,
                                 lo=[cx1 - size[0], cy1 - size[1]], hi=[cx0, cy0],
                                 footprint=size)
            t = m.t
            icp_iterations += m.icp_iterations
            if avoid_collisions and grid.collisions(t, si, sj, elements):
                # among the finalists, prefer the copy that collides least
                hits = [grid.collisions(a[:3], si, sj, elements) for a in m.alternatives]
                t = m.alternatives[int(np.argmin(hits)), :3].copy()
        else:
            t = cand[int(rng.integers(cand.shape[0]))]
        timing["match"] += time.perf_counter() - t0
        # (c) claim the free cells inside the translated exemplar box
        claim = grid.claim(t, si, sj)
        # (d, e) place, merge or drop every element of the copy centred in the claim
        t0 = time.perf_counter()
        failed = np.zeros_like(occ)
        for ex in ex_elements:
            p = Element(ex.V + t, ex.F, np.zeros(ex.V.shape[0], bool))
            ci, cj = grid.cell_of(p)
            centred = 0 <= ci < nx and 0 <= cj < ny and claim[ci, cj]
            if not centred:
                # also fill the claim with elements that only reach into it,
                # as long as they touch nothing
                i0, i1 = int(np.floor(p.lo[0] / cw)), int(np.floor(p.hi[0] / cw))
                j0, j1 = int(np.floor(p.lo[1] / ch)), int(np.floor(p.hi[1] / ch))
                if not (fill_gaps and claim[max(i0, 0):i1 + 1, max(j0, 0):j1 + 1].any()):
                    continue
            pieces = [p]
            if boundary == "clip" and (p.lo[0] < 0 or p.lo[1] < 0 or p.hi[0] > W or p.hi[1] > H):
                pieces = clipped_to(p, domain)
                if not pieces and centred:
                    stats.dropped["domain"] += 1
            if not centred:
                for q in pieces:
                    place_element(q, elements, domain, stats, optional=True)
                continue
            ok = [place_element(q, elements, domain, stats) for q in pieces]
            failed[ci, cj] = not all(ok) or not ok
        timing["merge"] += time.perf_counter() - t0
        # a cell whose element had to be dropped gets another chance (a new
        # copy matched to its now fuller neighbourhood), at most `retries` times
        again = claim & failed & (tries < retries)
        tries[again] += 1
        occ |= claim & ~again
    timing["synthesis"] = time.perf_counter() - t_start
    Vout, Fout, eids, fixed_out = concatenate_elements(elements)
    t0 = time.perf_counter()
    rep = quilt_report(Vout, Fout, eids, exemplar=(VE, FE, size), domain=domain,
                       merges=stats.merges, dropped=stats.dropped, seams=stats.seams,
                       placements=steps, gap_fills=stats.gap_fills,
                       icp_iterations=icp_iterations, cells=(nx, ny), cell=(cw, ch),
                       prefilled=sum(e.prefilled for e in elements),
                       element_problems=[closed_element_ok(e.V, e.F, intersections=False)
                                         for e in elements])
    timing["report"] = time.perf_counter() - t0
    rep.timings = {k: round(v, 4) for k, v in timing.items()}
    return QuiltResult(Vout, Fout, eids, fixed_out, rep,
                       np.array([e.prefilled for e in elements], dtype=bool))


def _closed(e: Element, domain) -> Element:
    """A prefilled element, capped where a domain side cut it open (caps are fixed)."""
    F2, cap, on_cut = capped(e.V, e.F, domain)
    if not cap.any():
        return e
    return Element(e.V, F2, e.fixed | on_cut, True, cap)


def _window_points(elements, x0, y0, x1, y1):
    """Vertices (and unit normals) of the texture inside the window rectangle."""
    Ps, Ns = [], []
    for e in elements:
        lo, hi = e.lo, e.hi
        if lo[0] > x1 or hi[0] < x0 or lo[1] > y1 or hi[1] < y0:
            continue
        sel = ((e.V[:, 0] >= x0) & (e.V[:, 0] <= x1) & (e.V[:, 1] >= y0) & (e.V[:, 1] <= y1))
        if sel.any():
            N = igl.per_vertex_normals(e.V, e.F)
            Ps.append(e.V[sel])
            Ns.append(N[sel])
    if not Ps:
        return np.zeros((0, 3)), np.zeros((0, 3))
    return np.concatenate(Ps), np.concatenate(Ns)
