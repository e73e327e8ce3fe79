"""Tile geometry into shell space: gather, weld across quads, shell map.

A tile vertex ``(u, v, w)`` on quad ``q`` is located in the deformed polycube
mesh (face + barycentric coordinates), which gives a base point ``x`` and an
interpolated unit offset direction ``d``; its shell position is
``x + w * scale * d``. Vertices on a tile side are welded *combinatorially*
before mapping: two tiles that meet on a global edge carry bit-identical side
vertices ``(t, w)`` (``t`` the coordinate along the edge, running the same way in
both quads), so the key ``(edge, t, w)`` merges them exactly and the shared
vertex is mapped once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geotex.tiles.tileset import TileSet

__all__ = ["gathered_tiles", "side_keys", "shell_positions", "MappedTiles", "mapped_tiles"]


def _ranges(starts: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """Concatenation of ``arange(s, s + c)`` for every pair, vectorized."""
    total = int(counts.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    offsets = np.cumsum(counts) - counts
    return np.repeat(starts - offsets, counts) + np.arange(total)


def gathered_tiles(tiles: TileSet, tile_of_quad: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Copies of the chosen tiles, one per quad, as one mesh in tile coordinates.

    Returns
    -------
    uvw : numpy.ndarray, (N, 3) float64
    quad_of_vertex : numpy.ndarray, (N,) int64
    faces : numpy.ndarray, (M, 3) int64
    """
    nv = np.diff(tiles.vertex_offsets)[tile_of_quad]
    nf = np.diff(tiles.face_offsets)[tile_of_quad]
    vidx = _ranges(tiles.vertex_offsets[tile_of_quad], nv)
    fidx = _ranges(tiles.face_offsets[tile_of_quad], nf)
    base = np.cumsum(nv) - nv
    faces = tiles.faces[fidx] + np.repeat(base, nf)[:, None]
    return tiles.vertices[vidx], np.repeat(np.arange(len(tile_of_quad)), nv), faces


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
    q = quad_of_vertex
    side = np.full(len(uvw), -1, dtype=np.int64)
    side[u == 0.0] = 3
    side[u == 1.0] = 1
    side[v == 0.0] = 0
    side[v == 1.0] = 2
    on = side >= 0
    s = side[on]
    t = np.where((s == 0) | (s == 2), u[on], v[on])
    edge = quad_edge[q[on], s]
    return on, np.stack([edge.astype(np.float64), t, w[on]], axis=1)


def shell_positions(V: np.ndarray, F: np.ndarray, D: np.ndarray, face: np.ndarray,
                    bary: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """Points ``x + offset * d`` over base faces.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
        Base vertices.
    F : numpy.ndarray, (m, 3) int64
    D : numpy.ndarray, (n, 3) float64
        Unit offset direction per base vertex.
    face : numpy.ndarray, (k,) int64
    bary : numpy.ndarray, (k, 3) float64
    offset : numpy.ndarray, (k,) float64
        Signed distance along the direction (world units).

    Returns
    -------
    numpy.ndarray, (k, 3) float64
    """
    corners = F[face]
    x = np.einsum("ki,kij->kj", bary, V[corners])
    d = np.einsum("ki,kij->kj", bary, D[corners])
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return x + offset[:, None] * d


@dataclass(frozen=True)
class MappedTiles:
    """Tile geometry mapped into a shell.

    Attributes
    ----------
    vertices : numpy.ndarray, (N, 3) float64
    faces : numpy.ndarray, (M, 3) int64
    quad_of_face : numpy.ndarray, (M,) int64
    welded : int
        Side vertices merged with their twin across a quad edge.
    """

    vertices: np.ndarray
    faces: np.ndarray
    quad_of_face: np.ndarray
    welded: int


def mapped_tiles(tiles: TileSet, tile_of_quad: np.ndarray, quad_edge: np.ndarray, locate,
                 V: np.ndarray, F: np.ndarray, D: np.ndarray, *, offset_scale: float
                 ) -> MappedTiles:
    """Map the chosen tiles of every quad into the shell and weld them.

    Parameters
    ----------
    tiles : TileSet
    tile_of_quad : numpy.ndarray, (q,) int64
    quad_edge : numpy.ndarray, (q, 4) int64
        Global edge of sides south, east, north, west of every quad.
    locate : callable
        ``locate(quad_ids (k,), uv (k, 2)) -> (face (k,), bary (k, 3))`` in the base.
    V, F, D : numpy.ndarray
        Base mesh and unit offset direction per base vertex.
    offset_scale : float
        World length of one unit of ``w``.

    Returns
    -------
    MappedTiles
    """
    uvw, quad_of_vertex, faces = gathered_tiles(tiles, tile_of_quad)
    on, keys = side_keys(uvw, quad_of_vertex, quad_edge)
    target = np.arange(len(uvw))
    if on.any():
        side_idx = np.flatnonzero(on)
        _, first, inv = np.unique(keys, axis=0, return_index=True, return_inverse=True)
        target[side_idx] = side_idx[first][inv.ravel()]
    keep = target == np.arange(len(uvw))
    new_index = np.cumsum(keep) - 1
    quad_of_face = quad_of_vertex[faces[:, 0]]
    faces = new_index[target][faces]
    kept = np.flatnonzero(keep)
    face, bary = locate(quad_of_vertex[kept], uvw[kept, :2])
    X = shell_positions(V, F, D, face, bary, uvw[kept, 2] * offset_scale)
    return MappedTiles(X, faces, quad_of_face, int(len(uvw) - len(kept)))
