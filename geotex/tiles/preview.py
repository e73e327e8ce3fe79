"""Pictures of tile sets: every tile laid out with its side colours, and a random tiling."""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np
from PIL import Image

from geotex.errors import InputError
from geotex.io.atomic import atomic_output
from geotex.mesh.primitives import box
from geotex.render import offscreen_pyvista
from geotex.tiles.frame import concatenated
from geotex.tiles.tileset import TileSet
from geotex.tiles.tiling import on_slab, planar_tiling, random_arrangement

__all__ = ["tiles_laid_out", "render_tiles", "render_tiling", "render_tileset"]

ELEMENT_COLOR = "#c9a86a"
PLATE_COLOR = "#8d8d8d"
#: side-bar colours: one hue family per axis class (X reds, Y blues, Z greens),
#: one shade per colour; an isotropic set uses the first family for every side
SIDE_COLORS = (("#d62728", "#ff9896", "#8c1c13", "#f4a261"),
               ("#1f77b4", "#aec7e8", "#17375e", "#6baed6"),
               ("#2ca02c", "#98df8a", "#145a14", "#b5cf6b"))


def tiles_laid_out(tiles: TileSet, *, columns: int | None = None, spacing: float = 0.25,
                   bars: bool = True):
    """Every tile on its own thin plate, in a grid with gaps between tiles.

    Tiles follow their order in the set (group by group), ``columns`` per row
    (default: 16 tiles of a group in 4 x 4 blocks side by side, three blocks
    a row). With ``bars``, a thin bar along every side shows its colour.

    Returns
    -------
    parts : dict of str -> tuple of (V (n, 3) float64, F (m, 3) int64)
        ``"elements"``, ``"plates"`` and one entry per side-bar colour
        (hex string).
    """
    n = len(tiles)
    blocks = n % 16 == 0 and n > 16
    columns = columns or (None if blocks else int(np.ceil(np.sqrt(n))))
    pitch = 1.0 + spacing
    t = max(tiles.depth, 0.02)
    Bv, Bf = box((0.0, 0.0, -t - 0.04), (1.0, 1.0, -0.5 * t))
    w = 0.045
    bar_boxes = [((0.0, -w - 0.02), (1.0, -0.02)), ((1.02, 0.0), (1.02 + w, 1.0)),
                 ((0.0, 1.02), (1.0, 1.02 + w)), ((-w - 0.02, 0.0), (-0.02, 1.0))]
    elements, plates, bar_parts = [], [], {}
    iso = tiles.isotropic
    for i in range(n):
        if columns is None:               # 4 x 4 blocks, three blocks per row
            b, k = divmod(i, 16)
            col = (b % 3) * 4 + k % 4 + 0.6 * (b % 3)
            row = (b // 3) * 4 + k // 4 + 0.6 * (b // 3)
        else:
            col, row = i % columns, i // columns
        off = np.array([col * pitch, -row * pitch, 0.0])
        V, F = tiles.tile(i)
        elements.append((V + off, F))
        plates.append((Bv + off, Bf))
        if bars:
            classes = tiles.groups[i, [0, 1, 0, 1]]
            for s in range(4):
                c = SIDE_COLORS[0 if iso else int(classes[s])][int(tiles.colors[i, s]) % 4]
                (x0, y0), (x1, y1) = bar_boxes[s]
                bar_parts.setdefault(c, []).append(box((x0 + off[0], y0 + off[1], -t - 0.04),
                                                       (x1 + off[0], y1 + off[1], 0.01)))
    out = {"elements": concatenated(elements), "plates": concatenated(plates)}
    out.update({c: concatenated(p) for c, p in bar_parts.items()})
    return out


def _render(parts: dict, path, *, size, title: str = "", zoom: float = 1.0,
            lines=None, view=(0.25, -1.0, 1.35)) -> Path:
    """Render named parts (key: colour or "elements"/"plates") looking down along ``-view``.

    Saved as a 256-colour PNG (the shading needs no more, the file is half the size).
    """
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise InputError(f"{path}: pictures are written as PNG; use a .png file name")
    pv = offscreen_pyvista()
    plotter = pv.Plotter(off_screen=True, window_size=(int(size[0]), int(size[1])),
                         border=False)
    try:
        plotter.set_background("white", top="#dfe6ee")
        plotter.enable_lightkit()
        allV = []
        for key, (V, F) in parts.items():
            if len(F) == 0:
                continue
            color = {"elements": ELEMENT_COLOR, "plates": PLATE_COLOR}.get(key, key)
            faces = np.hstack([np.full((len(F), 1), 3, dtype=np.int64), F]).ravel()
            plotter.add_mesh(pv.PolyData(np.asarray(V, dtype=np.float64), faces), color=color,
                             smooth_shading=False, specular=0.3, specular_power=20)
            allV.append(V)
        if lines is not None and len(lines[1]):
            P, E = lines
            cells = np.hstack([np.full((len(E), 1), 2, dtype=np.int64), E]).ravel()
            plotter.add_mesh(pv.PolyData(P, lines=cells), color="#333333", line_width=2)
        if title:
            plotter.add_text(title, position="upper_edge", font_size=13, color="#222222")
        P = np.vstack(allV)
        lo, hi = P.min(axis=0), P.max(axis=0)
        center = 0.5 * (lo + hi)
        extent = float(max(hi[0] - lo[0], hi[1] - lo[1]))
        direction = np.asarray(view, dtype=np.float64)
        direction /= np.linalg.norm(direction)
        plotter.camera_position = [tuple(center + direction * extent * 2.0), tuple(center),
                                   (0.0, 0.0, 1.0)]
        plotter.reset_camera()
        plotter.camera.zoom(zoom)
        plotter.reset_camera_clipping_range()
        plotter.enable_anti_aliasing("ssaa")
        image = plotter.screenshot(return_img=True)
    finally:
        plotter.close()
    buf = io.BytesIO()
    _palette(Image.fromarray(np.asarray(image))).save(buf, format="PNG")
    with atomic_output(path, "wb") as fh:
        fh.write(buf.getvalue())
    return path


def _palette(im):
    return im.convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT,
                                      dither=Image.Dither.NONE)


def render_tiles(tiles: TileSet, path, *, size=None) -> Path:
    """Picture of every tile of the set laid out, side colours shown as bars.

    Returns
    -------
    pathlib.Path
    """
    n = len(tiles)
    size = size or ((1800, 1250) if n > 16 else (1400, 1100))
    kinds = {"planar": "planar", "complete": "complete polycube", "isotropic": "isotropic",
             "directional": "directional base"}
    legend = ("bars: side colour (one family for all axes)" if tiles.isotropic else
              "bars: across strips red, along strips blue; darkest shade: the empty ridge"
              if tiles.directional else "bars: side colour (X red, Y blue, Z green)")
    title = (f"{tiles.name}: {kinds[tiles.kind]} set, {n} tile{'s' * (n != 1)}, colours "
             f"{','.join(str(c) for c in tiles.n_colors)}\n{legend}")
    if n > 16 and n % 16 == 0:
        title += "\nblocks of 16 tiles, left to right, top to bottom: groups " + " ".join(
            f"({a},{b})" for a, b in tiles.groups[::16].tolist())
    return _render(tiles_laid_out(tiles), path, size=size, title=title,
                   zoom=1.3 if n > 16 else 1.2 if n > 1 else 1.05, view=(0.15, -0.75, 1.6))


def render_tiling(tiles: TileSet, path, *, grid: int = 6, seed: int = 0, size=(1400, 1100),
                  tile_lines: bool = True) -> Path:
    """Picture of a random legal ``grid x grid`` tiling, welded and on a slab.

    Only the planar group (0, 1) is used. ``tile_lines`` draws the tile borders
    on the slab beside the tiling (thin lines just off its edge).

    Returns
    -------
    pathlib.Path
    """
    planar = _planar_part(tiles)
    arrangement = random_arrangement(planar, grid, grid, seed=seed)
    V, F = on_slab(*planar_tiling(planar, arrangement), (grid, grid))
    lines = None
    if tile_lines:       # ticks at the tile borders along the slab's front and left edges
        k = np.arange(grid + 1, dtype=np.float64)
        P = np.vstack([np.c_[k, np.full_like(k, -0.02), np.zeros_like(k)],
                       np.c_[k, np.full_like(k, -0.3), np.zeros_like(k)],
                       np.c_[np.full_like(k, -0.02), k, np.zeros_like(k)],
                       np.c_[np.full_like(k, -0.3), k, np.zeros_like(k)]])
        m = grid + 1
        E = np.r_[np.c_[np.arange(m), m + np.arange(m)],
                  np.c_[2 * m + np.arange(m), 3 * m + np.arange(m)]]
        lines = (P, E)
    title = f"{tiles.name}: random {grid} x {grid} tiling (seed {seed}), welded, on a slab"
    return _render({"elements": (V, F)}, path, size=size, title=title, zoom=1.3,
                   lines=lines)


def render_tileset(tiles: TileSet, path, *, grid: int = 6, seed: int = 0) -> Path:
    """One picture: the tiles laid out beside a random ``grid x grid`` tiling.

    Returns
    -------
    pathlib.Path
    """
    import tempfile

    path = Path(path)
    if path.suffix.lower() != ".png":
        raise InputError(f"{path}: pictures are written as PNG; use a .png file name")
    with tempfile.TemporaryDirectory() as tmp:
        a = render_tiles(tiles, Path(tmp) / "a.png", size=(1100, 900))
        b = render_tiling(tiles, Path(tmp) / "b.png", grid=grid, seed=seed, size=(1100, 900))
        left, right = np.asarray(Image.open(a).convert("RGB")), np.asarray(
            Image.open(b).convert("RGB"))
    buf = io.BytesIO()
    _palette(Image.fromarray(np.hstack([left, right]))).save(buf, format="PNG")
    with atomic_output(path, "wb") as fh:
        fh.write(buf.getvalue())
    return path


def _planar_part(tiles: TileSet) -> TileSet:
    """The tiles of group (0, 1), as a set of their own."""
    keep = np.flatnonzero((tiles.groups[:, 0] == 0) & (tiles.groups[:, 1] == 1))
    if keep.size == len(tiles):
        return tiles
    parts = [tiles.tile(int(i)) for i in keep]
    return TileSet.from_tiles(parts, tiles.groups[keep], tiles.colors[keep],
                              n_colors=(tiles.n_colors[0], tiles.n_colors[1], 0),
                              height=tiles.height, depth=tiles.depth, name=tiles.name,
                              metadata=tiles.metadata)
