"""Edge strips: the elements that cross a tile side, cut in two.

For every colour of every axis class one strip is taken from the exemplar: the
elements that cross a unit-length line segment, kept clear of the segment's
ends (the tile corners). A strip lives in its own coordinates ``(t, s, w)``:
``t`` runs along the segment (``0..1``), ``s`` across it, ``w`` is the height.
It is cut once at ``s = 0``; the tile on one side of an edge of that colour
receives the ``s >= 0`` half, its neighbour the ``s <= 0`` half, and the two
share their cut vertices bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geotex.errors import InputError
from geotex.mesh.topology import face_components
from geotex.tiles.clip import split_by_plane

__all__ = ["Strip", "element_boxes", "pick_strips", "corner_margin", "lattice_phase"]

GAP = 0.02          # clearance between elements and tile corners / other elements
CANDIDATES = 96     # random segment positions tried per colour


@dataclass(frozen=True)
class Strip:
    """One colour's edge strip, cut at ``s = 0``.

    Attributes
    ----------
    below, above : tuple of (V, F)
        The ``s <= 0`` and ``s >= 0`` halves in strip coordinates ``(t, s, w)``.
    origin : tuple of float
        Exemplar point where the segment starts.
    along : int
        Exemplar axis (0 = x, 1 = y) the segment runs along.
    boxes : numpy.ndarray, (k, 4) float64
        Footprints ``(t0, s0, t1, s1)`` of the strip's elements.
    """

    below: tuple
    above: tuple
    origin: tuple
    along: int
    boxes: np.ndarray


def element_boxes(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Element (connected component) of every face and each element's bounding box.

    Returns
    -------
    labels : numpy.ndarray, (m,) int64
    lo, hi : numpy.ndarray, (E, 3) float64
    """
    n, labels = face_components(F, len(V))
    corners = V[F]                                     # (m, 3, 3)
    lo = np.full((n, 3), np.inf)
    hi = np.full((n, 3), -np.inf)
    np.minimum.at(lo, labels, corners.min(axis=1))
    np.maximum.at(hi, labels, corners.max(axis=1))
    return labels, lo, hi


def corner_margin(lo: np.ndarray, hi: np.ndarray) -> float:
    """Distance from a tile corner that edge-strip elements keep clear of.

    Half the largest element footprint plus a gap, so that strips of two sides
    meeting at a corner never overlap.

    Raises
    ------
    InputError
        Elements too large for a unit tile.
    """
    half = 0.5 * float(np.max(hi[:, :2] - lo[:, :2]))
    margin = half + GAP
    if margin > 0.4:
        raise InputError(f"exemplar elements are {2 * half:.2f} wide; a tile is 1 x 1, so "
                         "elements must be under 0.76 wide (scale the exemplar down)")
    return margin


def lattice_phase(lo: np.ndarray, hi: np.ndarray, pitch: float) -> tuple[float, float]:
    """Phase of the exemplar's element lattice of period ``pitch`` in x and y.

    The element centres (of their boxes) taken modulo ``pitch``; the phase is
    the circular mean of the largest cluster (the centres within
    ``pitch / 5`` of the centre with most such neighbours, on the torus).

    Parameters
    ----------
    lo, hi : numpy.ndarray, (E, 3) float64
        Element bounding boxes.
    pitch : float

    Returns
    -------
    tuple of 2 float
        ``(phase_x, phase_y)`` in ``[0, pitch)``.
    """
    c = (0.5 * (lo[:, :2] + hi[:, :2])) % pitch
    d = np.abs(c[:, None, :] - c[None, :, :])
    d = np.minimum(d, pitch - d)
    close = np.hypot(d[..., 0], d[..., 1]) < pitch / 5
    members = close[int(np.argmax(close.sum(axis=1)))]
    z = np.exp(2j * np.pi * c[members] / pitch).mean(axis=0)
    phase = (np.angle(z) / (2 * np.pi) * pitch) % pitch
    return float(phase[0]), float(phase[1])


def _to_strip(P: np.ndarray, origin, along: int) -> np.ndarray:
    """Exemplar points -> strip coordinates (a rotation, never a mirror)."""
    d = P[..., :2] - np.asarray(origin)
    out = np.array(P, dtype=np.float64)
    if along == 0:
        out[..., 0], out[..., 1] = d[..., 0], d[..., 1]
    else:
        out[..., 0], out[..., 1] = d[..., 1], 0.0 - d[..., 0]
    return out


def pick_strips(V: np.ndarray, F: np.ndarray, size, *, count: int, along: int,
                rng: np.random.Generator, margin: float, taken=(),
                lattice=None) -> tuple[list[Strip], set]:
    """Choose ``count`` distinct edge strips from an exemplar.

    Parameters
    ----------
    V, F : numpy.ndarray
        Exemplar mesh; elements are its connected components.
    size : tuple of 2 float
        Exemplar extent.
    count : int
        Number of colours to make.
    along : int
        Exemplar axis the segments run along (0 = x, 1 = y).
    rng : numpy.random.Generator
    margin : float
        Corner clearance from :func:`corner_margin`.
    taken : iterable of frozenset
        Element sets already used by other strips; not reused.
    lattice : tuple (pitch, phase_x, phase_y), optional
        Segments start only on the exemplar's lattice points
        ``phase + (i, j) pitch``, so that the strip elements sit on the lattice
        of the tile (see :func:`lattice_phase`); otherwise anywhere.

    Returns
    -------
    strips : list of Strip
    used : set of frozenset
        ``taken`` plus the element sets of the new strips.
    """
    labels, lo, hi = element_boxes(V, F)
    lx, ly = size
    span = (lx, ly)[along]
    if span < 1.0:
        raise InputError(f"exemplar is {span:g} long along {'xy'[along]}; an edge strip "
                         "needs at least one tile length (1.0)")
    # element boxes in candidate strip coordinates, vectorized over candidates
    width = (ly, lx)[along]
    if lattice is None:
        a0 = rng.uniform(0.0, span - 1.0, CANDIDATES)
        a1 = rng.uniform(margin, width - margin, CANDIDATES)
    else:
        p, ph_along, ph_across = lattice[0], lattice[1 + along], lattice[2 - along]
        k = np.arange(np.ceil(-ph_along / p), np.floor((span - 1.0 - ph_along) / p) + 1)
        j = np.arange(np.ceil((margin - ph_across) / p),
                      np.floor((width - margin - ph_across) / p) + 1)
        K, J = np.meshgrid(k, j, indexing="ij")
        pick = rng.permutation(K.size)[:CANDIDATES]
        a0 = ph_along + K.ravel()[pick] * p
        a1 = ph_across + J.ravel()[pick] * p
    origin = np.stack([a0, a1], 1) if along == 0 else np.stack([a1, a0], 1)
    if along == 0:
        t0 = lo[None, :, 0] - origin[:, 0:1]
        t1 = hi[None, :, 0] - origin[:, 0:1]
        s0 = lo[None, :, 1] - origin[:, 1:2]
        s1 = hi[None, :, 1] - origin[:, 1:2]
    else:
        t0 = lo[None, :, 1] - origin[:, 1:2]
        t1 = hi[None, :, 1] - origin[:, 1:2]
        s0 = origin[:, 0:1] - hi[None, :, 0]
        s1 = origin[:, 0:1] - lo[None, :, 0]
    chosen = (s0 < -GAP / 4) & (s1 > GAP / 4) & (t0 >= margin) & (t1 <= 1.0 - margin)
    # other elements crossing the segment's ends are cut away by the corner rule;
    # score by the covered length of the segment
    cover = np.where(chosen, t1 - t0, 0.0).sum(axis=1)
    order = np.argsort(-cover, kind="stable")
    strips: list[Strip] = []
    used = set(taken)
    for c in order:
        if len(strips) == count:
            break
        members = frozenset(np.flatnonzero(chosen[c]).tolist())
        if not members or members in used:
            continue
        used.add(members)
        strips.append(_make_strip(V, F, labels, sorted(members), tuple(origin[c]), along,
                                  np.stack([t0[c], s0[c], t1[c], s1[c]], 1)[sorted(members)]))
    if len(strips) < count:
        raise InputError(f"the exemplar has only {len(strips)} distinct edge strips along "
                         f"{'xy'[along]} for {count} colours; use fewer colours or a larger "
                         "exemplar")
    return strips, used


def _make_strip(V, F, labels, members, origin, along, boxes) -> Strip:
    keep = np.isin(labels, members)
    Fs = F[keep]
    used = np.unique(Fs)
    remap = np.full(len(V), -1, dtype=np.int64)
    remap[used] = np.arange(len(used))
    Vs = _to_strip(V[used], origin, along)
    below, above = split_by_plane(Vs, remap[Fs], axis=1, value=0.0, snap=1e-4)
    return Strip(below, above, tuple(float(o) for o in origin), along, boxes)
