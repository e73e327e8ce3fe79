"""The jobs a batch can run on each part: one :class:`Job` entry per job in :data:`JOBS`.

Every job calls the library functions its ``geotex`` command calls (never the
command line itself) and writes its output through
:func:`geotex.printing.export_printable` (a temporary sibling, read back,
compared with the judged arrays, then renamed) or :func:`geotex.io.write_mesh`
(atomic too), so no half-written file ever sits under the final name.

A job function takes ``(part, shared, out)``: the :class:`~geotex.batch.manifest.Part`,
a dict of the heavy shared inputs it declared (``"tiles"``: the loaded
:class:`~geotex.tiles.TileSet`, ``"shell"``: the loaded
:class:`~geotex.shells.Shell`), and the output path (or None for a job that
writes nothing).  It returns a dict with any of ``faces``, ``tile_size``,
``coverage``, ``printable`` and raises a :class:`~geotex.errors.GeotexError`
with a one-line message when the part fails.

Adding a job is one entry: write ``def NAME_part(part, shared, out) -> dict``
and add ``Job("NAME", NAME_part, input="mesh", suffix=".stl", needs=(...),
shared=(...), help="...")`` to :data:`JOBS`.

The job functions import the libraries they run inside their bodies: ``geotex
--help`` reads :data:`JOBS` (the ``--job`` choices), and importing every
library at the top would make it load the whole package (mapping, image,
repair with pymeshlab, ...); a worker imports them once up front
(``Job.imports``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from geotex.errors import InputError, NotPrintableError

__all__ = ["Job", "JOBS", "SHARED_LOADERS", "texture_part", "map_part", "lapped_part",
           "displace_part", "check_part", "repair_part", "DISPLACE_DEPTH_MM"]

#: Relief depth of the ``displace`` job when a part gives no ``height`` (mm).
DISPLACE_DEPTH_MM = 1.0


@dataclass(frozen=True)
class Job:
    """One kind of work a batch can do on a part.

    Attributes
    ----------
    name : str
    run : callable
        ``run(part, shared, out) -> dict`` (see the module docstring).
    input : {"mesh", "shell"}
        What a part's ``input`` is: a mesh file, or a shell (catalog name or file).
    suffix : str or callable or None
        Output extension, or ``suffix(part) -> str``; None: no output file.
    needs : tuple of str
        Part fields that must be set (``"tiles"``, ``"image"``).
    shared : tuple of str
        Heavy inputs loaded once on the client and scattered to every worker,
        keys of :data:`SHARED_LOADERS`.
    help : str
    imports : tuple of str
        Modules a worker imports once when the batch starts (so the first
        part's time is its own, not the import of the libraries).
    """

    name: str
    run: Callable
    input: str = "mesh"
    suffix: object = ".stl"
    needs: tuple = ()
    shared: tuple = ()
    help: str = ""
    imports: tuple = ()

    def output_name(self, part) -> str | None:
        """File name of the part's output in the output folder (None: no output)."""
        suffix = self.suffix(part) if callable(self.suffix) else self.suffix
        return None if suffix is None else f"{part.name}{suffix}"

    def shared_keys(self, part) -> list[tuple[str, str]]:
        """``(kind, name)`` of the shared inputs this part uses."""
        return [(kind, SHARED_FIELDS[kind](part)) for kind in self.shared]

    def validate(self, part) -> None:
        """Raise an InputError naming where the part was declared if a need is missing."""
        for need in self.needs:
            if getattr(part, need) in (None, ""):
                flag = {"tiles": "--tiles or a 'tiles' column"}.get(need, f"a '{need}' column")
                raise InputError(f"{part.source}: the {self.name} job needs {need}: "
                                 f"give {flag}")


def _scaled_mesh(part):
    """The part's mesh, scaled to ``size_mm`` when given."""
    # lazy: `geotex --help` loads this table (module docstring)
    from geotex.io import read_mesh

    mesh = read_mesh(part.input)
    if part.size_mm is not None and mesh.n_vertices:
        ext = float(np.ptp(mesh.vertices, axis=0).max())
        if ext > 0:
            mesh = mesh.with_geometry(mesh.vertices * (part.size_mm / ext), mesh.faces)
    return mesh


def _coverage(shell) -> float | None:
    value = shell.polycube.diagnostics.coverage.get("within_tile")
    return None if value is None else round(float(value), 4)


def _textured(part, shell, tiles, out) -> dict:
    # lazy: `geotex --help` loads this table (module docstring)
    from geotex.mapping import texture_height, textured_solid
    from geotex.printing import StagedWrite, export_printable

    height = texture_height(shell, tiles, part.height)
    with StagedWrite(out, name=part.name) as staged:     # written while it is checked
        result = textured_solid(shell, tiles, height=height, seed=part.seed,
                                on_stored=staged)
        rep = export_printable(out, result.vertices, result.faces, name=part.name,
                               report=result.report, staged=staged)
    return {"faces": int(rep.faces), "tile_size": round(float(shell.tile_size), 6),
            "coverage": _coverage(shell), "printable": bool(rep.printable)}


def texture_part(part, shared, out) -> dict:
    """``geotex texture``: build the part's shell, lay the tile set over it, write the solid."""
    # lazy: `geotex --help` loads this table (module docstring)
    from geotex.shells import build_shell

    mesh = _scaled_mesh(part)
    shell = build_shell(mesh.vertices, mesh.faces, tile_size=part.tile_size, name=part.name,
                        source=Path(part.input).name,
                        recipe={"source": Path(part.input).name})
    return _textured(part, shell, shared["tiles"], out)


def map_part(part, shared, out) -> dict:
    """``geotex map``: lay the tile set over a ready shell (scaled to ``size_mm``)."""
    shell = shared["shell"]
    if part.size_mm is not None:
        # lazy: `geotex --help` loads this table (module docstring)
        from geotex.shells import scaled_shell

        shell = scaled_shell(shell, part.size_mm / float(np.ptp(shell.base_vertices,
                                                                 axis=0).max()))
    return _textured(part, shell, shared["tiles"], out)


def lapped_part(part, shared, out) -> dict:
    """``geotex lapped``: a textured GLB, or with ``height`` a printable relief STL."""
    # lazy: `geotex --help` loads this table (module docstring)
    from geotex.image.lapped import default_scale, lapped_texture
    from geotex.image.patches import texture_patches

    mesh = _scaled_mesh(part)
    if mesh.n_faces == 0:
        raise InputError(f"{part.input}: the mesh has no faces")
    V, F = mesh.vertices, mesh.faces
    patches = texture_patches(part.image, seed=part.seed)
    lapped = lapped_texture(V, F, patches, scale=default_scale(V), seed=part.seed)
    coverage = round(float(np.mean(np.minimum(lapped.coverage, 1.0))), 4)
    if part.height is None:
        # lazy: `geotex --help` loads this table (module docstring)
        from geotex.image.atlas import textured_mesh
        from geotex.io import write_mesh

        write_mesh(out, textured_mesh(V, F, lapped, name=part.name))
        return {"faces": int(F.shape[0]), "coverage": coverage}
    # lazy: `geotex --help` loads this table (module docstring)
    from geotex.check import check_mesh
    from geotex.image.displace import displace
    from geotex.printing import export_printable

    Vd, Fd = displace(V, F, lapped, depth=part.height)
    report = check_mesh(Vd, Fd)
    if not report.printable:
        raise NotPrintableError(f"{part.input}: the relief is not printable "
                                f"({'; '.join(report.reasons)}); try a smaller height", report)
    rep = export_printable(out, Vd, Fd, name=part.name, report=report)
    return {"faces": int(rep.faces), "coverage": coverage, "printable": bool(rep.printable)}


def displace_part(part, shared, out) -> dict:
    """``geotex displace``: a height map (library name or image) as a printable relief.

    ``height`` is the relief depth in mm (default :data:`DISPLACE_DEPTH_MM`),
    ``size_mm`` scales the part first; the triplanar mapping and the other
    defaults of the command.
    """
    from geotex.displace import displace_file

    depth = DISPLACE_DEPTH_MM if part.height is None else part.height
    res = displace_file(part.input, part.image, out, depth=depth, size_mm=part.size_mm,
                        seed=part.seed)
    return {"faces": int(res.faces.shape[0]), "printable": bool(res.report.printable)}


def check_part(part, shared, out) -> dict:
    """``geotex check``: the validity report; a part that is not printable fails."""
    # lazy: `geotex --help` loads this table (module docstring)
    from geotex.check import check_mesh
    from geotex.io import read_mesh

    mesh = read_mesh(part.input)
    report = check_mesh(mesh.vertices, mesh.faces, source=str(part.input))
    if not report.printable:
        raise NotPrintableError(f"{part.input}: not printable ({'; '.join(report.reasons)})",
                                report)
    return {"faces": int(report.faces), "printable": True}


def repair_part(part, shared, out) -> dict:
    """``geotex repair``: repair and write the result only when printable and faithful."""
    # lazy: `geotex --help` loads this table (module docstring)
    from geotex.printing import export_printable
    from geotex.repair import repair_mesh

    mesh = _scaled_mesh(part)
    result = repair_mesh(mesh.vertices, mesh.faces)
    if not result.report.printable:
        raise NotPrintableError(f"{part.input}: still not printable after repair "
                                f"({'; '.join(result.report.reasons)})", result.report)
    if not result.faithful:
        raise NotPrintableError(f"{part.input}: the repair changed the solid "
                                f"({'; '.join(result.warnings)}); run 'geotex repair --force' "
                                "on it to accept", result.report)
    rep = export_printable(out, result.vertices, result.faces, name=part.name)
    return {"faces": int(rep.faces), "printable": bool(rep.printable)}


def _lapped_suffix(part) -> str:
    return ".glb" if part.height is None else ".stl"


def _load_tiles(name):
    # lazy: `geotex --help` loads this table (module docstring)
    from geotex.tiles.catalog import load_named

    return load_named(name)


def _load_shell(name):
    # lazy: `geotex --help` loads this table (module docstring)
    from geotex.shells import load_named

    return load_named(name)


#: Heavy shared inputs: kind -> loader of a catalog name or file.
SHARED_LOADERS: dict[str, Callable] = {"tiles": _load_tiles, "shell": _load_shell}
#: kind -> the part field naming it.
SHARED_FIELDS: dict[str, Callable] = {"tiles": lambda p: p.tiles, "shell": lambda p: p.input}

#: The job table: name -> Job.
JOBS: dict[str, Job] = {j.name: j for j in (
    Job("texture", texture_part, needs=("tiles",), shared=("tiles",),
        help="build the shell of a base mesh and lay a tile set over it (geotex texture)",
        imports=("geotex.shells", "geotex.mapping", "geotex.printing")),
    Job("map", map_part, input="shell", needs=("tiles",), shared=("tiles", "shell"),
        help="lay a tile set over a ready shell (geotex map)",
        imports=("geotex.shells", "geotex.mapping", "geotex.printing")),
    Job("lapped", lapped_part, suffix=_lapped_suffix, needs=("image",),
        help="lapped image texture: GLB, or a relief STL with a height (geotex lapped)",
        imports=("geotex.image.lapped", "geotex.image.atlas", "geotex.printing")),
    Job("displace", displace_part, needs=("image",),
        help="height-map relief: a library map or an image, depth = height mm (geotex displace)",
        imports=("geotex.displace", "geotex.printing")),
    Job("check", check_part, suffix=None,
        help="validity report; parts that are not printable fail (geotex check)",
        imports=("geotex.check", "geotex.io")),
    Job("repair", repair_part,
        help="repair towards a printable solid (geotex repair)",
        imports=("geotex.repair", "geotex.printing")),
)}
