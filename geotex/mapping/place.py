"""Tile geometry into shell space: gather, weld across quads, shell map.

A tile vertex ``(u, v, w)`` on quad ``q`` is located in the shell's fitted
polycube surface (face + barycentric coordinates), which gives a base point
``x`` and an interpolated unit offset direction ``d``; its shell position is
``x + w * scale * d``. Vertices on a tile side are welded *combinatorially*
before mapping: two tiles that meet on a global edge carry bit-identical side
vertices ``(t, w)`` (``t`` the coordinate along the edge, running the same way in
both quads), so the key ``(edge, t, w)`` merges them exactly and the shared
vertex is mapped once. Elements left open (next to a quad that received no
tile) are dropped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geotex.shells.locate import interpolated
from geotex.tiles.tileset import TileSet

__all__ = ["gathered_tiles", "side_keys", "MappedTiles", "mapped_tiles"]


def _ranges(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Concatenation of ``arange(s, s + c)`` for every pair, vectorized."""
    total = int(counts.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    offsets = np.cumsum(counts) - counts
    return np.repeat(starts - offsets, counts) + np.arange(total)


def gathered_tiles(tiles: TileSet, tile_of_quad: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Copies of the chosen tiles, one per quad (``-1``: none), in tile coordinates.

    Returns
    -------
    uvw : numpy.ndarray, (N, 3) float64
    quad_of_vertex : numpy.ndarray, (N,) int64
    faces : numpy.ndarray, (M, 3) int64
    """
    quads = np.flatnonzero(tile_of_quad >= 0)
    t = tile_of_quad[quads]
    nv = np.diff(tiles.vertex_offsets)[t]
    nf = np.diff(tiles.face_offsets)[t]
    vidx = _ranges(tiles.vertex_offsets[t], nv)
    fidx = _ranges(tiles.face_offsets[t], nf)
    base = np.cumsum(nv) - nv
    faces = tiles.faces[fidx] + np.repeat(base, nf)[:, None]
    return tiles.vertices[vidx], np.repeat(quads, nv), faces


def side_keys(uvw: np.ndarray, quad_of_vertex: np.ndarray, quad_edge: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
    """Weld keys of the vertices that lie on a tile side.

    Returns
    -------
    on_side : numpy.ndarray, (N,) bool
    keys : numpy.ndarray, (k, 3) float64
        ``(global edge, t, w)`` of the side vertices, in order.
    """
    u, v, w = uvw.T
    side = np.full(len(uvw), -1, dtype=np.int64)
    side[u == 0.0] = 3
    side[u == 1.0] = 1
    side[v == 0.0] = 0
    side[v == 1.0] = 2
    on = side >= 0
    s = side[on]
    t = np.where((s == 0) | (s == 2), u[on], v[on])
    edge = quad_edge[quad_of_vertex[on], s]
    return on, np.stack([edge.astype(np.float64), t, w[on]], axis=1)


@dataclass(frozen=True)
class MappedTiles:
    """Tile geometry mapped into a shell.

    Attributes
    ----------
    vertices : numpy.ndarray, (N, 3) float64
    faces : numpy.ndarray, (M, 3) int64
        Closed elements only.
    welded : int
        Side vertices merged with their twin across a quad edge.
    dropped_faces : int
        Faces of elements left open (beside a quad without a tile).
    """

    vertices: np.ndarray
    faces: np.ndarray
    welded: int
    dropped_faces: int


def mapped_tiles(shell, tiles: TileSet, tile_of_quad: np.ndarray, *, scale: float
                 ) -> MappedTiles:
    """Map the chosen tiles of every quad into the shell and weld them.

    Parameters
    ----------
    shell : Shell
    tiles : TileSet
    tile_of_quad : numpy.ndarray, (q,) int64
        Tile of every quad, ``-1`` for a quad left bare.
    scale : float
        World length of one unit of ``w``.

    Returns
    -------
    MappedTiles
    """
    from geotex.tiles.tiling import closed_elements

    pc = shell.polycube
    uvw, quad_of_vertex, faces = gathered_tiles(tiles, tile_of_quad)
    on, keys = side_keys(uvw, quad_of_vertex, pc.quad_edge)
    target = np.arange(len(uvw))
    if on.any():
        side_idx = np.flatnonzero(on)
        _, first, inv = np.unique(keys, axis=0, return_index=True, return_inverse=True)
        target[side_idx] = side_idx[first][inv.ravel()]
    keep = target == np.arange(len(uvw))
    new_index = np.cumsum(keep) - 1
    faces = new_index[target][faces]
    kept = np.flatnonzero(keep)
    face, bary = pc.locate(quad_of_vertex[kept], uvw[kept, :2])
    x = interpolated(pc.Y, pc.F, face, bary)
    d = interpolated(shell.D, pc.F, face, bary)
    d /= np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)
    X = x + (uvw[kept, 2] * float(scale))[:, None] * d
    V2, F2 = closed_elements(X, faces)
    return MappedTiles(V2, F2, int(len(uvw) - len(kept)), int(len(faces) - len(F2)))
