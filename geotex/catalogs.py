"""What the tile-set and shell catalogs share: recipes beside the files, name lookup.

A catalog is a package folder holding ``NAME.npz`` files and ``recipes.json``
(``{name: recipe}``); a user names an entry or gives a file path.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

from geotex.errors import InputError, MissingFileError

__all__ = ["Catalog"]


@dataclass(frozen=True)
class Catalog:
    """A catalog folder: ``NAME.npz`` files and their ``recipes.json``.

    Attributes
    ----------
    folder : pathlib.Path
    what : str
        What an entry is, in messages (``"shell"``, ``"tile set"``).
    """

    folder: Path
    what: str

    def recipes(self) -> dict:
        """Return ``{name: recipe}`` of the catalog (empty if it has none)."""
        f = Path(self.folder) / "recipes.json"
        if not f.is_file():
            return {}
        return json.loads(f.read_text())

    def recipe(self, name: str, table: dict | None = None) -> dict:
        """The recipe of entry ``name`` (from ``table`` instead of ``recipes.json`` if given).

        Raises
        ------
        InputError
            Unknown name; the message lists the catalog.
        """
        table = self.recipes() if table is None else table
        if name not in table:
            raise InputError(f"{name!r} is not in the {self.what} catalog; choose one of "
                             f"{', '.join(sorted(table)) or 'none'}")
        return table[name]

    def file(self, name: str) -> Path:
        """Where catalog entry ``name`` is stored (it may not exist yet)."""
        return Path(self.folder) / f"{name}.npz"

    def path(self, name_or_path) -> Path:
        """Resolve an existing file path, or a catalog name, to a file.

        Raises
        ------
        MissingFileError
            Neither an existing file nor a catalog name; the message lists the catalog.
        """
        p = Path(name_or_path)
        if p.is_file():
            return p
        q = self.file(str(name_or_path))
        if p.suffix == "" and q.is_file():
            return q
        names = ", ".join(sorted(self.recipes())) or "none"
        raise MissingFileError(f"{p}: no such {self.what} file or catalog name "
                               f"(catalog: {names})")

    def entries(self) -> list[dict]:
        """``name``, ``file``, ``bytes`` (0 when not built) and ``recipe`` of every entry, by name."""
        out = []
        for name, recipe in sorted(self.recipes().items()):
            f = self.file(name)
            out.append({"name": name, "file": str(f),
                        "bytes": f.stat().st_size if f.is_file() else 0, "recipe": recipe})
        return out
