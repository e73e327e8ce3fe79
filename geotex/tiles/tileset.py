"""The tile set record and its file format.

A tile set file is a compressed ``.npz`` holding every tile's geometry in one
flat layout (float32 positions, int32 faces, per-tile offsets), the group and
side colours of every tile, and a JSON metadata string (exemplar, colours,
height, depth, seed, the recipe that rebuilds the set, geotex version).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from geotex.errors import InputError, MeshFileError
from geotex.io.records import read_record, write_record

__all__ = ["TileSet", "save_tileset", "load_tileset", "tile_rng", "FORMAT_VERSION"]

FORMAT_VERSION = 1
_DATE = (1980, 1, 1, 0, 0, 0)       # fixed member time stamps: same set, same bytes
_KEYS = ("vertices", "faces", "vertex_offsets", "face_offsets", "groups", "colors")


@dataclass(frozen=True)
class TileSet:
    """A geometric Wang tile set: every tile's geometry in texture space.

    Attributes
    ----------
    vertices : numpy.ndarray, (N, 3) float64
        Positions of all tiles (values exactly representable in float32). A tile
        covers ``[0, 1]^2`` in ``(u, v)``; ``w`` is the height (elements reach
        down to ``-depth`` so they fuse with a base).
    faces : numpy.ndarray, (M, 3) int64
        Faces of all tiles, indices local to their tile.
    vertex_offsets, face_offsets : numpy.ndarray, (T + 1,) int64
        Tile ``i`` owns ``vertices[vertex_offsets[i]:vertex_offsets[i + 1]]``
        and ``faces[face_offsets[i]:face_offsets[i + 1]]``.
    groups : numpy.ndarray, (T, 2) int64
        Axis class of the south/north sides and of the west/east sides
        (see :mod:`geotex.tiles.colors`).
    colors : numpy.ndarray, (T, 4) int64
        Colour of sides south, east, north, west.
    n_colors : tuple of 3 int
        Colours of the X, Y, Z classes (``n_z = 0`` for a planar set).
    height, depth : float
        Largest ``w`` of the elements, and how far they reach below ``w = 0``.
    name : str
    metadata : dict
        JSON-serialisable: exemplar, recipe, seed, build statistics.
    """

    vertices: np.ndarray
    faces: np.ndarray
    vertex_offsets: np.ndarray
    face_offsets: np.ndarray
    groups: np.ndarray
    colors: np.ndarray
    n_colors: tuple
    height: float
    depth: float
    name: str = ""
    metadata: dict = field(default_factory=dict)

    def __len__(self) -> int:
        return len(self.groups)

    @property
    def planar(self) -> bool:
        """True for a planar set (group (0, 1) only, ``n_z = 0``)."""
        return self.n_colors[2] == 0

    @property
    def isotropic(self) -> bool:
        """True for an isotropic set: one colour class for all axes (False for old files).

        Its ``n^4`` tiles are group (0, 1), ``n_colors`` is ``(n, n, n)``, and a
        side of colour ``c`` is seamless with every other side of colour ``c``,
        whatever the axis classes, so the set covers a closed polycube when the
        group is ignored.
        """
        return bool(self.metadata.get("isotropic", False))

    @property
    def directional(self) -> bool:
        """True for a directional set (:mod:`geotex.tiles.directional`), base or oriented.

        A base set is group (0, 1) with side colours ``0..n`` (``n``, the
        *ridge*, has empty sides) and ``n_colors`` ``(n, n, 0)``; its oriented
        form holds the six groups, turned to follow a flow on a closed polycube.
        """
        return bool(self.metadata.get("directional"))

    @property
    def kind(self) -> str:
        """``"planar"``, ``"complete"``, ``"isotropic"`` or ``"directional"``."""
        if self.directional:
            return "directional"
        return "isotropic" if self.isotropic else "planar" if self.planar else "complete"

    def tile(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """Return tile ``i`` as ``(V (n, 3) float64, F (m, 3) int64)``."""
        v0, v1 = self.vertex_offsets[i], self.vertex_offsets[i + 1]
        f0, f1 = self.face_offsets[i], self.face_offsets[i + 1]
        return self.vertices[v0:v1], self.faces[f0:f1]

    def index(self) -> dict:
        """Map ``(a, b, s, e, n, w)`` (group and side colours) to the tile number."""
        return {tuple(g) + tuple(c): i for i, (g, c) in
                enumerate(zip(self.groups.tolist(), self.colors.tolist()))}

    @classmethod
    def from_tiles(cls, tiles, groups, colors, **kwargs) -> "TileSet":
        """Assemble a set from a list of ``(V, F)`` tiles; positions rounded to float32."""
        nv = np.array([len(V) for V, _ in tiles], dtype=np.int64)
        nf = np.array([len(F) for _, F in tiles], dtype=np.int64)
        V = np.vstack([V for V, _ in tiles]).astype(np.float32).astype(np.float64)
        F = np.vstack([F for _, F in tiles]).astype(np.int64)
        return cls(V, F, np.concatenate([[0], np.cumsum(nv)]),
                   np.concatenate([[0], np.cumsum(nf)]),
                   np.asarray(groups, dtype=np.int64).reshape(-1, 2),
                   np.asarray(colors, dtype=np.int64).reshape(-1, 4), **kwargs)


def tile_rng(seed: int, t: int) -> np.random.Generator:
    """The random generator of tile ``t`` of a set built with ``seed``.

    The ``t``-th child of ``SeedSequence(seed).spawn``: independent of the
    strips' generator (``default_rng(seed)``) and of every other tile's.
    """
    return np.random.default_rng(np.random.SeedSequence(int(seed), spawn_key=(int(t),)))


def save_tileset(path, tiles: TileSet) -> None:
    """Write a tile set file (compressed ``.npz``), atomically.

    The same set always gives the same bytes (fixed member time stamps), so a
    catalog set rebuilt from its recipe can be compared byte for byte.

    Parameters
    ----------
    path : str or os.PathLike
        Output path; ``.npz`` is the only format.
    tiles : TileSet

    Raises
    ------
    InputError
        An oriented directional set (only its base set is stored).
    """
    if tiles.metadata.get("directional", {}).get("oriented"):
        raise InputError("save_tileset: save the directional base set, not its oriented "
                         "form (geotex.tiles.directional.oriented_tileset makes it on load)")
    meta = dict(tiles.metadata)
    meta.update(format="geotex-tileset", format_version=FORMAT_VERSION, name=tiles.name,
                n_colors=list(tiles.n_colors), height=tiles.height, depth=tiles.depth)
    arrays = {"vertices": tiles.vertices.astype(np.float32),
              "faces": tiles.faces.astype(np.int32),
              "vertex_offsets": tiles.vertex_offsets.astype(np.int64),
              "face_offsets": tiles.face_offsets.astype(np.int64),
              "groups": tiles.groups.astype(np.int8), "colors": tiles.colors.astype(np.int8),
              "metadata": np.array(json.dumps(meta, sort_keys=True))}
    write_record(path, arrays, compressed=True, date_time=_DATE, kind="tile set")


def load_tileset(path) -> TileSet:
    """Read a tile set file written by :func:`save_tileset`.

    Raises
    ------
    MissingFileError
        No such file.
    MeshFileError
        Not a tile set file, truncated, corrupted or inconsistent.
    """
    path = Path(path)
    data, meta = read_record(path, kind="tile set", format="geotex-tileset", arrays=_KEYS,
                             hint="rebuild it with 'geotex tiles build'")
    if meta.get("format_version", 0) > FORMAT_VERSION:
        raise MeshFileError(path, f"tile set format {meta['format_version']} is newer than "
                            "this geotex; upgrade geotex")
    V = data["vertices"].astype(np.float64)
    F = data["faces"].astype(np.int64)
    vo, fo = data["vertex_offsets"].astype(np.int64), data["face_offsets"].astype(np.int64)
    groups, colors = data["groups"].astype(np.int64), data["colors"].astype(np.int64)
    _validate(path, V, F, vo, fo, groups, colors)
    try:
        n_colors = tuple(int(c) for c in meta.pop("n_colors"))
        name = str(meta.pop("name", path.stem))
        height, depth = float(meta.pop("height")), float(meta.pop("depth"))
    except (KeyError, TypeError, ValueError):
        raise MeshFileError(path, "tile set metadata lacks n_colors, height or depth") from None
    if len(n_colors) != 3 or (groups.min() < 0 or groups.max() > 2):
        raise MeshFileError(path, "tile set groups or colour counts are corrupted")
    side_class = groups[:, [0, 1, 0, 1]]
    # a directional set has one more colour per class than it draws: the ridge
    extra = 1 if meta.get("directional") else 0
    if colors.min() < 0 or np.any(colors >= np.asarray(n_colors)[side_class] + extra):
        raise MeshFileError(path, "tile set side colours exceed the colour counts")
    for k in ("format", "format_version"):
        meta.pop(k, None)
    return TileSet(V, F, vo, fo, groups, colors, n_colors, height, depth, name, meta)


def _validate(path, V, F, vo, fo, groups, colors) -> None:
    T = len(groups)
    ok = (V.ndim == 2 and V.shape[1] == 3 and F.ndim == 2 and F.shape[1] == 3
          and vo.shape == (T + 1,) and fo.shape == (T + 1,) and colors.shape == (T, 4)
          and groups.shape == (T, 2) and T > 0)
    if not ok:
        raise MeshFileError(path, "tile set arrays have inconsistent shapes")
    if (vo[0] != 0 or fo[0] != 0 or vo[-1] != len(V) or fo[-1] != len(F)
            or np.any(np.diff(vo) < 0) or np.any(np.diff(fo) < 0)):
        raise MeshFileError(path, "tile set offsets are corrupted")
    if not np.isfinite(V).all():
        raise MeshFileError(path, "tile set has non-finite coordinates")
    counts = np.repeat(np.diff(vo), np.diff(fo))
    if len(F) and (F.min() < 0 or np.any(F.max(axis=1) >= counts)):
        raise MeshFileError(path, "tile set faces index vertices outside their tile")
