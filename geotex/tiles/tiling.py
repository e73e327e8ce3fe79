"""Random legal tilings of the plane, welded into one geometric texture."""

from __future__ import annotations

import manifold3d
import numpy as np

from geotex.errors import InputError
from geotex.mesh.needles import SLIVER_TOLERANCE, needle_free
from geotex.mesh.solid import arrays_of_manifold, manifold_of
from geotex.mesh.topology import compacted, edge_topology, face_components
from geotex.quilting.elements import capped
from geotex.tiles.tileset import TileSet

__all__ = ["random_arrangement", "planar_tiling", "welded", "closed_elements", "on_slab",
           "BORDERS"]

BORDERS = ("drop", "open", "cap")


def random_arrangement(tiles: TileSet, width: int, height: int, *,
                       seed: int = 0) -> np.ndarray:
    """Pick a tile for every cell of a ``width x height`` grid at random, legally.

    Every grid edge gets a random colour of its axis class (horizontal edges X,
    vertical edges Y); each cell takes the tile of group (0, 1) with its four
    edge colours, so neighbours always agree.

    Returns
    -------
    numpy.ndarray, (height, width) int64
        Tile numbers; row 0 is the bottom row (smallest v).

    Raises
    ------
    InputError
        Bad grid size, or the set lacks a needed tile.
    """
    if width < 1 or height < 1:
        raise InputError(f"grid must be at least 1 x 1, got {width} x {height}")
    nx, ny = tiles.n_colors[0], tiles.n_colors[1]
    rng = np.random.default_rng(seed)
    horizontal = rng.integers(0, nx, size=(height + 1, width))
    vertical = rng.integers(0, ny, size=(height, width + 1))
    index = tiles.index()
    out = np.empty((height, width), dtype=np.int64)
    for j in range(height):
        for i in range(width):
            key = (0, 1, horizontal[j, i], vertical[j, i + 1], horizontal[j + 1, i],
                   vertical[j, i])
            if key not in index:
                raise InputError(f"tile set {tiles.name!r} has no tile with colours {key[2:]}")
            out[j, i] = index[key]
    return out


def welded(V: np.ndarray, F: np.ndarray, on_seam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Merge vertices flagged ``on_seam`` that sit at exactly the same position.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    on_seam : numpy.ndarray, (n,) bool
        Candidates for merging (tile-side vertices); others are kept as they are.

    Returns
    -------
    V2, F2 : numpy.ndarray
    """
    seam = np.flatnonzero(on_seam)
    _, first, inverse = np.unique(V[seam], axis=0, return_index=True, return_inverse=True)
    target = np.arange(len(V))
    target[seam] = seam[first][inverse.ravel()]
    keep = np.zeros(len(V), dtype=bool)
    keep[target] = True
    new_index = np.cumsum(keep) - 1
    return V[keep], new_index[target][F]


def closed_elements(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Drop the connected components that have open boundary edges.

    Elements cut by the outer border of a finite tiling are open; this keeps
    the closed ones.

    Returns
    -------
    V2, F2 : numpy.ndarray
        Compacted.
    """
    topo = edge_topology(F, len(V))
    _, labels = face_components(F, len(V))
    open_faces = np.zeros(len(F), dtype=bool)
    edge_open = topo.face_count[topo.half_to_edge] == 1
    open_faces[edge_open.reshape(-1, 3).any(axis=1)] = True
    bad = np.unique(labels[open_faces])
    return compacted(V, F[~np.isin(labels, bad)])


def planar_tiling(tiles: TileSet, arrangement: np.ndarray, *, border: str | None = None
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Lay tiles out on the grid and weld them.

    Parameters
    ----------
    tiles : TileSet
    arrangement : numpy.ndarray, (h, w) int64
        Tile numbers per cell (see :func:`random_arrangement`).
    border : {"drop", "open", "cap"}, optional
        What to do with the elements cut open by the outer border of the
        tiling: drop them (the result is a set of closed elements), keep them
        open, or close their openings with flat caps in the border planes
        (:func:`geotex.quilting.elements.capped`; for sets whose elements run
        across the whole tiling, such as the weave's strands). Default: the
        set's ``metadata["tiling_border"]``, else ``"drop"``.

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
        Positions in tile units; cell ``(j, i)`` covers ``[i, i+1] x [j, j+1]``.
    F : numpy.ndarray, (m, 3) int64

    Raises
    ------
    InputError
        Unknown ``border``, or an opening that cannot be capped.
    """
    if border is None:
        border = tiles.metadata.get("tiling_border", "drop")
    if border not in BORDERS:
        raise InputError(f"border: expected one of {', '.join(BORDERS)}, got {border!r}")
    h, w = arrangement.shape
    parts_v, parts_f, seam = [], [], []
    offset = 0
    for j in range(h):
        for i in range(w):
            V, F = tiles.tile(int(arrangement[j, i]))
            parts_v.append(V + np.array([i, j, 0.0]))
            parts_f.append(F + offset)
            seam.append((V[:, 0] == 0.0) | (V[:, 0] == 1.0) | (V[:, 1] == 0.0)
                        | (V[:, 1] == 1.0))
            offset += len(V)
    V, F = welded(np.vstack(parts_v), np.vstack(parts_f), np.concatenate(seam))
    if border == "cap":
        F, _, _ = capped(V, F, (0.0, 0.0, float(w), float(h)))
        return closed_elements(V, F)
    return closed_elements(V, F) if border == "drop" else (V, F)


def on_slab(V: np.ndarray, F: np.ndarray, size, *, thickness: float = 0.2
            ) -> tuple[np.ndarray, np.ndarray]:
    """Union a planar texture with the slab ``[0, w] x [0, h] x [-thickness, 0]``.

    The needle triangles the boolean leaves where elements graze the slab's
    top are removed (:func:`geotex.mesh.needles.needle_free` at
    :data:`~geotex.mesh.needles.SLIVER_TOLERANCE` of the diagonal), as after the
    main job's union: rounded to float32 they would fold onto their neighbours.

    Returns
    -------
    V, F : numpy.ndarray
        One printable solid (manifold3d boolean union).
    """
    slab = manifold3d.Manifold.cube([float(size[0]), float(size[1]), thickness]
                                    ).translate([0.0, 0.0, -thickness])
    U, G = arrays_of_manifold(slab + manifold_of(V, F))
    diag = float(np.linalg.norm(np.ptp(U, axis=0))) if len(U) else 0.0
    U, G, _ = needle_free(U, G, tolerance=SLIVER_TOLERANCE * diag)
    return U, G
