"""Pictures of tile sets: every tile laid out, and a random tiling."""

from __future__ import annotations

import numpy as np

from geotex.tiles.frame import concatenated
from geotex.tiles.tileset import TileSet
from geotex.tiles.tiling import on_slab, planar_tiling, random_arrangement

__all__ = ["tiles_laid_out", "render_tileset"]


def tiles_laid_out(tiles: TileSet, *, columns: int | None = None, spacing: float = 0.2
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every tile on its own thin plate, in a grid with gaps between tiles.

    Returns
    -------
    V, F : numpy.ndarray
        The tiles and their plates.
    tile_of_face : numpy.ndarray, (m,) int64
        Tile number of every face (for colouring).
    """
    from geotex.mesh.primitives import box

    n = len(tiles)
    columns = columns or int(np.ceil(np.sqrt(n)))
    parts, owner = [], []
    Bv, Bf = box((0.0, 0.0, -0.04), (1.0, 1.0, -0.5 * tiles.depth))
    for i in range(n):
        V, F = tiles.tile(i)
        off = np.array([(i % columns) * (1 + spacing), -(i // columns) * (1 + spacing), 0.0])
        parts += [(V + off, F), (Bv + off, Bf)]
        owner += [np.full(len(F) + len(Bf), i)]
    V, F = concatenated(parts)
    return V, F, np.concatenate(owner)


def render_tileset(tiles: TileSet, path, *, grid: int = 6, seed: int = 0):
    """Picture: the tiles laid out (planar group) beside a random ``grid x grid`` tiling.

    Returns
    -------
    pathlib.Path
    """
    from geotex.render import Panel, render_panels

    group = np.flatnonzero((tiles.groups[:, 0] == 0) & (tiles.groups[:, 1] == 1))
    planar = _subset(tiles, group)
    V, F, owner = tiles_laid_out(planar)
    arrangement = random_arrangement(planar, grid, grid, seed=seed)
    Vt, Ft = on_slab(*planar_tiling(planar, arrangement), (grid, grid))
    shown = f"{len(planar)} of {len(tiles)} tiles" if len(planar) < len(tiles) else \
        f"{len(tiles)} tiles"
    return render_panels([
        Panel(V, F, scalars=owner % 7, cmap="tab10",
              title=f"{tiles.name}: {shown} (X,Y colours {tiles.n_colors[:2]})"),
        Panel(Vt, Ft, title=f"random {grid} x {grid} tiling, welded, on a slab"),
    ], path, size=(1000, 800))


def _subset(tiles: TileSet, keep: np.ndarray) -> TileSet:
    parts = [tiles.tile(int(i)) for i in keep]
    return TileSet.from_tiles(parts, tiles.groups[keep], tiles.colors[keep],
                              n_colors=(tiles.n_colors[0], tiles.n_colors[1], 0),
                              height=tiles.height, depth=tiles.depth, name=tiles.name,
                              metadata=tiles.metadata)
