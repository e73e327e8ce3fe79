"""Frames and global edges of polycube grid quads.

Quad frame convention
---------------------
A chart with label axis ``a`` and sign ``s`` has the in-plane axes
``(a1, a2) = ((a+1)%3, (a+2)%3)`` when ``s = +1`` and ``((a+2)%3, (a+1)%3)``
when ``s = -1``; ``e1 = +unit(a1)``, ``e2 = +unit(a2)`` and ``e1 x e2`` is the
chart's outward normal (a right-handed frame).  A quad is the grid cell
``[i, i+1] x [j, j+1]`` of the chart plane in ``(a1, a2)`` tile coordinates;
its corners, counter-clockwise around the outward normal, are
``c0 = (i, j)``, ``c1 = (i+1, j)``, ``c2 = (i+1, j+1)``, ``c3 = (i, j+1)``
and the tile point ``(u, v)`` lies at ``(i + u, j + v)``.  Quad edge ``k``
runs from ``c_k`` to ``c_(k+1)%4``: ``0`` south (``v = 0``, along ``+e1``),
``1`` east (``u = 1``, along ``+e2``), ``2`` north (``v = 1``, along ``-e1``),
``3`` west (``u = 0``, along ``-e2``).  Two quads sharing an edge traverse it
in opposite directions (the surface is closed and oriented).

Because ``e1`` and ``e2`` always point along *increasing* coordinates, the
tile coordinate along any side (``u`` on south/north, ``v`` on east/west)
grows with the global coordinate of the edge's axis: two quads sharing a
global edge see the same point at the same ``t``, whichever sides (and charts,
across a polycube edge) they use.  Colour matching therefore never needs to
reverse a side.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from geotex.errors import GeotexError

__all__ = ["QuadLayout", "chart_axes", "quad_edges"]


@dataclass(frozen=True)
class QuadLayout:
    """Connectivity of a polycube's tile quads: no world geometry.

    What the mapping needs to colour edges and choose tiles, and what a shell
    file stores; the positions live on :class:`~geotex.param.polycube.PolyCube`.

    Attributes
    ----------
    quad_grid : (q, res + 1, res + 1) int64
        Sub-grid vertex at tile point ``(i / res, j / res)`` of every quad.
    quad_label : (q,) int64
        Outward normal of every quad (``0 +X, 1 -X, 2 +Y, 3 -Y, 4 +Z, 5 -Z``).
    quad_corners : (q, 4, 3) int64
        Corners in integer tile units, counter-clockwise about the outward
        normal (the frame of this module's docstring).
    quad_edge : (q, 4) int64
        Global edge of sides south, east, north, west.
    quad_edge_forward : (q, 4) bool
        True when the quad runs along its edge toward increasing coordinate.
    edge_axis : (E,) int64
        Axis class of every global edge (0 X, 1 Y, 2 Z).
    edge_quads, edge_sides : (E, 2) int64
        The two quads of every edge and the side index in each.
    """

    quad_grid: np.ndarray
    quad_label: np.ndarray
    quad_corners: np.ndarray
    quad_edge: np.ndarray
    quad_edge_forward: np.ndarray
    edge_axis: np.ndarray
    edge_quads: np.ndarray
    edge_sides: np.ndarray

    @classmethod
    def of_quads(cls, corners: np.ndarray, labels: np.ndarray, grid: np.ndarray
                 ) -> "QuadLayout":
        """The layout of quads given by their corners, labels and sub-grid.

        Raises
        ------
        GeotexError
            If the quads do not form a closed manifold surface (see :func:`quad_edges`).
        """
        qe, qf, eax, eq, es = quad_edges(corners)
        return cls(quad_grid=grid, quad_label=labels, quad_corners=corners, quad_edge=qe,
                   quad_edge_forward=qf, edge_axis=eax, edge_quads=eq, edge_sides=es)

    @property
    def n_quads(self) -> int:
        """Number of quads ``q``."""
        return int(self.quad_label.size)

    @property
    def n_edges(self) -> int:
        """Number of global quad edges ``E``."""
        return int(self.edge_axis.size)

    @property
    def res(self) -> int:
        """Sub-cells along a tile side."""
        return int(self.quad_grid.shape[1] - 1)

    @property
    def quad_axes(self) -> np.ndarray:
        """In-plane axes ``(a1, a2)`` of every quad's frame, ``(q, 2)`` int64."""
        _, a1, a2 = chart_axes(self.quad_label)
        return np.stack([a1, a2], axis=1)

    @property
    def face_quad(self) -> np.ndarray:
        """Quad of every sub-grid face, ``(q * 2 res^2,)`` int64 (faces run quad by quad)."""
        return np.arange(self.n_quads * 2 * self.res ** 2, dtype=np.int64) // (2 * self.res ** 2)


def chart_axes(label: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normal axis, first and second in-plane axes of labels, each ``(k,)`` int64."""
    label = np.asarray(label, np.int64)
    a = label // 2
    pos = label % 2 == 0
    a1 = np.where(pos, (a + 1) % 3, (a + 2) % 3)
    a2 = np.where(pos, (a + 2) % 3, (a + 1) % 3)
    return a, a1, a2


def quad_edges(corners: np.ndarray):
    """Global edges of the quads.

    Returns
    -------
    quad_edge : (q, 4) int64
        Global id of quad edge ``k`` (from corner ``k`` to ``(k+1)%4``).
    quad_edge_forward : (q, 4) bool
        True when the quad traverses the edge toward increasing coordinate.
    edge_axis : (E,) int64
        Axis class (0 X, 1 Y, 2 Z) of every global edge.
    edge_quads : (E, 2) int64
        The two quads of every edge (lower quad index first).
    edge_sides : (E, 2) int64
        Local edge index (0..3) of the edge in each of those quads.

    Raises
    ------
    GeotexError
        If a grid edge is not shared by exactly two quads.
    """
    q = corners.shape[0]
    a = corners
    b = np.roll(corners, -1, axis=1)
    lo = np.minimum(a, b).reshape(-1, 3)
    hi = np.maximum(a, b).reshape(-1, 3)
    key = np.concatenate([lo, hi], axis=1)
    uniq, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    if (counts != 2).any():
        raise GeotexError(f"{int((counts != 2).sum())} polycube grid edges are not shared by "
                          "exactly two quads (the polycube surface is not a closed manifold)")
    d = (b - a).reshape(-1, 3)
    axis_of_half = np.argmax(np.abs(d), axis=1)
    forward = d[np.arange(d.shape[0]), axis_of_half] > 0
    E = uniq.shape[0]
    edge_axis = np.zeros(E, np.int64)
    edge_axis[inv] = axis_of_half
    order = np.argsort(inv, kind="stable")
    edge_quads = (order // 4).reshape(E, 2)
    edge_sides = (order % 4).reshape(E, 2)
    return (inv.reshape(q, 4).astype(np.int64), forward.reshape(q, 4), edge_axis,
            edge_quads.astype(np.int64), edge_sides.astype(np.int64))
