"""Tile frames: the four edge-strip halves placed on the sides of a tile."""

from __future__ import annotations

import numpy as np

from geotex.errors import InputError
from geotex.mesh.topology import concatenated, face_components
from geotex.tiles.colors import EAST, NORTH, SOUTH, WEST
from geotex.tiles.strips import CornerPatch, Strip

__all__ = ["placed_half", "placed_band", "frame_of", "concatenated"]


def placed_half(strip: Strip, side: int) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray]:
    """The half of ``strip`` that lies inside a tile, placed on ``side``.

    Placement is a rotation plus a translation (never a mirror), with the strip's
    ``t`` along +u (south, north) or +v (west, east) and its ``s`` axis a quarter
    turn counter-clockwise from ``t``; cut vertices land exactly on the side.

    Returns
    -------
    mesh : tuple of (V (n, 3) float64, F (m, 3) int64)
    boxes : numpy.ndarray, (k, 4) float64
        Footprints ``(u0, v0, u1, v1)`` of the placed elements.
    """
    (V, F) = strip.above if side in (SOUTH, EAST) else strip.below
    b = strip.boxes
    out = _on_side(V, side)
    if side == SOUTH:
        boxes = np.stack([b[:, 0], np.zeros(len(b)), b[:, 2], b[:, 3]], 1)
    elif side == NORTH:
        boxes = np.stack([b[:, 0], 1.0 + b[:, 1], b[:, 2], np.ones(len(b))], 1)
    elif side == WEST:
        boxes = np.stack([np.zeros(len(b)), b[:, 0], -b[:, 1], b[:, 2]], 1)
    else:
        boxes = np.stack([1.0 - b[:, 3], b[:, 0], np.ones(len(b)), b[:, 2]], 1)
    return (out, F), boxes


def placed_band(strip: Strip, side: int) -> tuple[np.ndarray, np.ndarray]:
    """The band elements of ``strip`` (its ``band``) inside a tile, placed on ``side``.

    The same placement as :func:`placed_half`: the ``s > 0`` band on the
    south and east sides, the ``s < 0`` band on the north and west sides.

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
        Whole closed elements; empty without a band.
    """
    if strip.band is None:
        return np.zeros((0, 3), dtype=np.float64), np.zeros((0, 3), dtype=np.int64)
    (V, F) = strip.band[1] if side in (SOUTH, EAST) else strip.band[0]
    return _on_side(V, side), F


def _on_side(V: np.ndarray, side: int) -> np.ndarray:
    """Strip coordinates ``(t, s, w)`` -> tile coordinates for a strip on ``side``."""
    t, s = V[:, 0], V[:, 1]
    out = V.copy()
    if side == SOUTH:
        out[:, 0], out[:, 1] = t, s
    elif side == NORTH:
        out[:, 0], out[:, 1] = t, 1.0 + s
    elif side == WEST:
        out[:, 0], out[:, 1] = 0.0 - s, t
    elif side == EAST:
        out[:, 0], out[:, 1] = 1.0 - s, t
    else:
        raise InputError(f"side must be 0..3, got {side}")
    return out


def frame_of(strips_ab, colors, patch: CornerPatch | None = None
             ) -> tuple[tuple[np.ndarray, np.ndarray], np.ndarray]:
    """The frame of one tile.

    Parameters
    ----------
    strips_ab : tuple of (list of Strip, list of Strip)
        Strips of the south/north class and of the west/east class.
    colors : sequence of 4 int
        Colours of sides south, east, north, west.
    patch : CornerPatch, optional
        The patch every corner holds (:func:`geotex.tiles.strips.corner_patch`):
        its piece on the tile's side of both lines through each corner is
        added, moved by whole tile units (so the pieces of neighbouring
        tiles meet bit for bit on the sides).

    Returns
    -------
    mesh : tuple of (V, F)
    boxes : numpy.ndarray, (k, 4) float64
        Element footprints of the frame.
    """
    sn, we = strips_ab
    parts, boxes = [], []
    for side, strip in ((SOUTH, sn[colors[0]]), (EAST, we[colors[1]]),
                        (NORTH, sn[colors[2]]), (WEST, we[colors[3]])):
        mesh, b = placed_half(strip, side)
        parts.append(mesh)
        boxes.append(b)
    if patch is not None:
        for key, (du, dv) in (("ne", (0.0, 0.0)), ("nw", (1.0, 0.0)), ("sw", (1.0, 1.0)),
                              ("se", (0.0, 1.0))):
            V, F = patch.pieces[key]
            if not len(F):
                continue
            V = V.copy()
            V[:, 0] += du
            V[:, 1] += dv
            parts.append((V, F))
            n, labels = face_components(F, len(V))
            corners = V[F][:, :, :2]
            lo = np.full((n, 2), np.inf)
            hi = np.full((n, 2), -np.inf)
            np.minimum.at(lo, labels, corners.min(axis=1))
            np.maximum.at(hi, labels, corners.max(axis=1))
            boxes.append(np.c_[lo, hi])
    return concatenated(parts), np.vstack(boxes)
