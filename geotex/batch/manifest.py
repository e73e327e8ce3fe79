"""Parts of a batch: a manifest (CSV) or a folder, read into :class:`Part` records.

A manifest is a CSV file with a header row.  One column is required:

``input``
    The part's input: a mesh file for the ``texture``, ``lapped``, ``check``
    and ``repair`` jobs, a shell (catalog name or ``.npz`` file) for ``map``.
    Relative paths are relative to the manifest's folder.

and the others are optional (an empty cell means "the batch default"):

``name``
    Output stem (default: the input's stem); unique within the batch.
``job``
    One of :data:`geotex.batch.jobs.JOBS` (default: the batch's job).
``tiles``
    Tile set: catalog name or ``.npz`` file (``texture``, ``map``).
``size_mm``
    Scale the part so that its largest extent is this many millimetres.
``tile_size``
    Tile side in mm at print size (``texture``; default automatic).
``height``
    Texture height in mm (``texture``, ``map``); relief depth for ``lapped``
    (then a printable STL relief is written instead of a textured GLB) and for
    ``displace`` (default 1 mm).
``seed``
    Non-negative integer (default 0).
``image``
    Example image for ``lapped``.

Lines starting with ``#`` are comments.  A folder stands for a manifest with
one row per mesh file in it (or per shell ``.npz`` for the ``map`` job), in
name order, all with the batch defaults.
"""

from __future__ import annotations

import csv
import math
from dataclasses import asdict, dataclass, replace
from pathlib import Path

from geotex.batch.jobs import JOBS
from geotex.errors import InputError, MissingFileError

__all__ = ["Part", "read_parts", "read_manifest", "folder_parts", "COLUMNS"]

#: Manifest columns, in the order they are documented.
COLUMNS = ("input", "name", "job", "tiles", "size_mm", "tile_size", "height", "seed", "image")
MAX_SIZE_MM = 10000.0


@dataclass(frozen=True)
class Part:
    """One part of a batch and its options.

    Attributes
    ----------
    name : str
        Unique name; the output is ``OUTDIR/NAME.EXT``.
    input : str
        Mesh file (absolute or as given), or a shell name / file for ``map``.
    job : str
        Job name (:data:`geotex.batch.jobs.JOBS`).
    tiles : str or None
        Tile set name or file.
    size_mm, tile_size, height : float or None
        Millimetres (see the module docstring).
    seed : int
    image : str or None
    source : str
        Where the part was declared (``manifest.csv:4`` or the folder), for messages.
    """

    name: str
    input: str
    job: str
    tiles: str | None = None
    size_mm: float | None = None
    tile_size: float | None = None
    height: float | None = None
    seed: int = 0
    image: str | None = None
    source: str = ""

    def options(self) -> dict:
        """The options that determine the output (compared by ``resume``)."""
        d = asdict(self)
        d.pop("source")
        return d


def _number(text: str, column: str, where: str, *, upper: float = math.inf) -> float | None:
    text = text.strip()
    if not text:
        return None
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and 0 < value <= upper):
        bound = f" (at most {upper:g})" if math.isfinite(upper) else ""
        raise InputError(f"{where}: column {column}: {text!r} is not a positive number of "
                         f"millimetres{bound}")
    return value


def _seed(text: str, where: str, default: int) -> int:
    text = text.strip()
    if not text:
        return default
    if not text.isdigit():
        raise InputError(f"{where}: column seed: {text!r} is not a non-negative integer")
    return int(text)


def _path(text: str, base: Path) -> str:
    p = Path(text)
    return str(p if p.is_absolute() else base / p)


def _check_names(parts: list[Part]) -> list[Part]:
    seen: dict[str, str] = {}
    for p in parts:
        if p.name in seen:
            raise InputError(f"{p.source}: part name {p.name!r} is used twice (also at "
                             f"{seen[p.name]}); give the rows distinct 'name' values")
        seen[p.name] = p.source
    return parts


def read_manifest(path, *, job: str = "texture", tiles: str | None = None,
                  seed: int = 0) -> list[Part]:
    """Read a CSV manifest into parts.

    Parameters
    ----------
    path : str or os.PathLike
        The manifest (``.csv``).
    job : str, optional
        Job of the rows that do not name one.
    tiles : str, optional
        Tile set of the rows that do not name one.
    seed : int, optional
        Seed of the rows that do not give one.

    Returns
    -------
    list of Part

    Raises
    ------
    MissingFileError
        No such file.
    InputError
        No ``input`` column, an unknown column or job, a bad number, an empty
        manifest or a name used twice; the message names the file and line.
    """
    path = Path(path)
    if not path.is_file():
        raise MissingFileError(f"{path}: no such manifest file")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{path}: cannot read the manifest ({exc.__class__.__name__}); "
                         "give a UTF-8 CSV file") from None
    rows = [(i + 1, line) for i, line in enumerate(text.splitlines())
            if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise InputError(f"{path}: the manifest is empty; give a header row with an 'input' "
                         "column and one row per part")
    reader = csv.reader([line for _, line in rows])
    try:
        table = list(reader)
    except csv.Error as exc:
        raise InputError(f"{path}: not a valid CSV file ({exc})") from None
    header = [h.strip().lower() for h in table[0]]
    unknown = [h for h in header if h not in COLUMNS]
    if unknown:
        raise InputError(f"{path}:{rows[0][0]}: unknown column {unknown[0]!r}; the columns are "
                         f"{', '.join(COLUMNS)}")
    if "input" not in header:
        raise InputError(f"{path}:{rows[0][0]}: no 'input' column in the header row")
    if len(set(header)) != len(header):
        raise InputError(f"{path}:{rows[0][0]}: a column is named twice")
    if len(table) < 2:
        raise InputError(f"{path}: the manifest has a header but no parts")
    base = path.parent
    parts = []
    for (lineno, _), cells in zip(rows[1:], table[1:]):
        where = f"{path}:{lineno}"
        if len(cells) != len(header):
            raise InputError(f"{where}: {len(cells)} cells, the header has {len(header)}")
        row = dict(zip(header, cells))
        src = row["input"].strip()
        if not src:
            raise InputError(f"{where}: column input is empty")
        row_job = row.get("job", "").strip() or job
        if row_job not in JOBS:
            raise InputError(f"{where}: column job: {row_job!r} is not one of "
                             f"{', '.join(JOBS)}")
        spec = JOBS[row_job]
        value = src if (spec.input == "shell" and not src.lower().endswith(".npz")) \
            else _path(src, base)
        row_tiles = row.get("tiles", "").strip() or tiles
        if row_tiles and row_tiles.lower().endswith(".npz"):
            row_tiles = _path(row_tiles, base)
        image = row.get("image", "").strip() or None
        part = Part(name=row.get("name", "").strip() or Path(src).stem, input=value,
                    job=row_job, tiles=row_tiles,
                    size_mm=_number(row.get("size_mm", ""), "size_mm", where,
                                    upper=MAX_SIZE_MM),
                    tile_size=_number(row.get("tile_size", ""), "tile_size", where),
                    height=_number(row.get("height", ""), "height", where),
                    seed=_seed(row.get("seed", ""), where, seed),
                    image=_path(image, base) if image else None, source=where)
        spec.validate(part)
        parts.append(part)
    return _check_names(parts)


def folder_parts(folder, *, job: str = "texture", tiles: str | None = None, seed: int = 0,
                 size_mm: float | None = None) -> list[Part]:
    """One part per input file of a folder (mesh files, or shell ``.npz`` for ``map``).

    Returns
    -------
    list of Part
        In file-name order.

    Raises
    ------
    MissingFileError
        No such folder.
    InputError
        Unknown job, no input file in the folder, or two files with the same stem.
    """
    # lazy: `geotex --help` imports geotex.batch; geotex.io would add ~25-50 ms to it
    from geotex.io import READ_FORMATS

    folder = Path(folder)
    if not folder.is_dir():
        raise MissingFileError(f"{folder}: no such folder")
    if job not in JOBS:
        raise InputError(f"job {job!r} is not one of {', '.join(JOBS)}")
    spec = JOBS[job]
    exts = (".npz",) if spec.input == "shell" else READ_FORMATS
    files = sorted(p for p in folder.iterdir()
                   if p.is_file() and p.suffix.lower() in exts and not p.name.startswith("."))
    if not files:
        raise InputError(f"{folder}: no input files ({', '.join(exts)}) in the folder")
    parts = [Part(name=p.stem, input=str(p), job=job, tiles=tiles, size_mm=size_mm, seed=seed,
                  source=str(p)) for p in files]
    for p in parts:
        spec.validate(p)
    return _check_names(parts)


def read_parts(path, *, job: str = "texture", tiles: str | None = None, seed: int = 0,
               size_mm: float | None = None) -> list[Part]:
    """Parts of a manifest file or a folder (see :func:`read_manifest`, :func:`folder_parts`).

    ``size_mm`` is the default print size of the rows that do not give one.
    """
    path = Path(path)
    if path.is_dir():
        return folder_parts(path, job=job, tiles=tiles, seed=seed, size_mm=size_mm)
    parts = read_manifest(path, job=job, tiles=tiles, seed=seed)
    if size_mm is not None:
        parts = [p if p.size_mm is not None else replace(p, size_mm=size_mm) for p in parts]
    return parts
