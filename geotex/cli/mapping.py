"""``geotex map`` and ``geotex texture``: tile sets over shells, as printable solids."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from geotex.cli._common import (EXIT_NOT_PRINTABLE, EXIT_OK, UsageError, flag_error,
                                guard_output, preload_compiled)

HELP_MAP = "lay a tile set over a shell and write the printable textured solid"
HELP_TEXTURE = "one shot: build the shell of a base mesh and lay a tile set over it"


def _output_options(p):
    p.add_argument("-o", "--output", required=True,
                   help="solid to write (.stl or .3mf; .obj/.ply/.off also accepted)")
    p.add_argument("--height", type=float, default=None,
                   help="texture height in mm at print size (default: the tiles' own "
                   "proportions, at most the shell's safe height)")
    p.add_argument("--seed", type=int, default=0, help="seed of the tile layout (default 0)")
    p.add_argument("--size-mm", type=float, default=None,
                   help="scale the base so its largest extent is this many millimetres before "
                   "texturing (default: the base's units are millimetres)")
    p.add_argument("--keep-failed", action="store_true",
                   help="if the result is not printable, still write it for inspection as "
                   "NAME.NOT-PRINTABLE.EXT (exit status 1)")
    p.add_argument("--picture", default=None, help="also write a picture (.png)")
    p.add_argument("--up", choices=("x", "y", "z"), default="z",
                   help="up axis of the picture, and of the flow of a directional tile set "
                        "(scales hang toward -up on the sides; default z; the bundled "
                        "samples are y-up)")
    p.add_argument("--report", default=None, help="also write the statistics (.json)")


def register(sub):
    m = sub.add_parser("map", help=HELP_MAP, description=HELP_MAP + ". TILES and SHELL "
                       "are catalog names ('geotex tiles list', 'geotex shell list') or files.")
    m.add_argument("--tiles", required=True, help="tile set: catalog name or .npz file")
    m.add_argument("--shell", required=True, help="shell: catalog name or .npz file")
    _output_options(m)
    m.set_defaults(run=run_map)

    t = sub.add_parser("texture", help=HELP_TEXTURE, description=HELP_TEXTURE + ". BASE is "
                       "a closed mesh file (run 'geotex repair' on it first if needed).")
    t.add_argument("base", help="closed base mesh file")
    t.add_argument("--tiles", required=True, help="tile set: catalog name or .npz file")
    t.add_argument("--tile-size", type=float, default=None,
                   help="tile side in mm at print size (default: automatic, the largest size "
                   "from 1/12 of the largest extent down that resolves and covers the shape)")
    t.add_argument("--shell-out", default=None, help="also save the shell (.npz)")
    _output_options(t)
    t.set_defaults(run=run_texture)


def _check_outputs(args, *inputs):
    from geotex.printing import PRINT_FORMATS

    out = guard_output(args.output, *inputs)
    if out.suffix.lower() not in PRINT_FORMATS:
        raise UsageError(f"{out}: cannot write a print as '{out.suffix}'; use .stl or .3mf")
    extra = {}
    for opt, ext in (("picture", ".png"), ("report", ".json"), ("shell_out", ".npz")):
        value = getattr(args, opt, None)
        if value is None:
            continue
        path = guard_output(value, *inputs)
        if path.suffix.lower() != ext:
            raise UsageError(f"{path}: --{opt.replace('_', '-')} needs a {ext} file name")
        if path.resolve() == out.resolve():
            raise UsageError(f"{path}: the same file as -o")
        extra[opt] = path
    if args.seed < 0:
        raise UsageError(f"--seed {args.seed}: give a non-negative integer")
    if args.size_mm is not None and not (0 < args.size_mm <= 10000):
        raise UsageError(f"--size-mm {args.size_mm}: give a size in (0, 10000] mm")
    if args.height is not None and not (0 < args.height < float("inf")):
        raise UsageError(f"--height {args.height}: give a positive height in mm")
    if getattr(args, "tile_size", None) is not None and not (0 < args.tile_size < float("inf")):
        raise UsageError(f"--tile-size {args.tile_size}: give a positive size in mm")
    return out, extra


#: Print sizes (largest extent, mm) outside which a part is probably in the wrong unit.
PRINT_SIZE_RANGE = (10.0, 1000.0)


def warn_print_size(extent_mm: float) -> None:
    """Warn (stderr) when a part's largest extent looks like a unit mix-up."""
    lo, hi = PRINT_SIZE_RANGE
    if not (lo <= extent_mm <= hi):
        print(f"geotex: warning: the part is {extent_mm:.4g} mm across (its coordinates are "
              f"read as millimetres); use --size-mm to give its print size", file=sys.stderr)


def _texture_height(args, shell, tiles):
    """The texture height, with the CLI's wording when --height is out of range."""
    from geotex.mapping import texture_height

    if args.height is not None and args.height > shell.max_height * (1 + 1e-12):
        raise UsageError(f"--height {args.height:g} mm is above the shell's safe height "
                         f"{shell.max_height:.4g} mm (a taller texture would intersect "
                         "itself); use a smaller --height"
                         + (" or a larger --tile-size" if hasattr(args, "tile_size") else ""))
    return texture_height(shell, tiles, args.height)


def _finish(args, shell, tiles, out, extra, *, label: str, seconds=None) -> int:
    import time

    import numpy as np

    from geotex.errors import NotPrintableError
    from geotex.io.atomic import atomic_output
    from geotex.mapping import MAP_PROGRESS, textured_solid
    from geotex.printing import StagedWrite, export_printable
    from geotex.progress import stage_bar

    from geotex.errors import InputError

    height = _texture_height(args, shell, tiles)
    if tiles.directional:                   # turned to the flow of --up
        from geotex.tiles.directional import oriented_tileset
        tiles = oriented_tileset(tiles, up="xyz".index(args.up))
    warn_print_size(float(np.ptp(shell.base_vertices, axis=0).max()))
    # the STL is written (to a hidden sibling, read back, compared) while the
    # check judges it; it takes its name only if the verdict says printable
    with StagedWrite(out, name=label) as staged:
        try:
            with stage_bar(len(MAP_PROGRESS), "map") as bar:
                result = textured_solid(shell, tiles, height=height, seed=args.seed,
                                        progress=bar, on_stored=staged)
        except InputError as exc:
            flags = {"height": "--height", "seed": "--seed"}
            if hasattr(args, "tile_size"):                  # 'geotex texture' builds the shell
                flags["tile size"] = "--tile-size"
            raise flag_error(exc, flags) from None
        V, F, rep = result.vertices, result.faces, result.report
        s = result.stats
        print(f"{label}: {s.quads} tiles of {shell.tile_size:.3g} mm ({s.bare_quads} bare), "
              f"{s.elements} elements {s.height:.3g} mm high, {s.faces} faces")
        if s.elements_lowered or s.elements_propped:
            print(f"  re-seated: {s.elements_lowered} floating elements lowered onto the base, "
                  f"{s.elements_propped} stood on it with a post")
        if s.elements_floating or s.elements_folded:
            print(f"  left out: {s.elements_folded} elements folded by the shell map, "
                  f"{s.elements_floating} that do not reach the base")
        status = EXIT_OK
        seconds = dict(seconds or {}, **s.seconds)
        t = time.perf_counter()
        try:
            rep = export_printable(out, V, F, name=label, report=rep, staged=staged)
            # the write overlaps the check: this is the time it took beyond it
            seconds["write"] = round(time.perf_counter() - t, 3)
            print(f"wrote {out} (printable as written: checked on the file's own coordinates)")
        except NotPrintableError as exc:
            print(f"geotex: error: {out}: not written, not printable as stored "
                  f"({'; '.join(exc.report.reasons)})", file=sys.stderr)
            status = EXIT_NOT_PRINTABLE
            if not args.keep_failed:
                return status
            kept = out.with_name(f"{out.stem}.NOT-PRINTABLE{out.suffix}")
            rep = export_printable(kept, V, F, name=label, report=exc.report, force=True)
            print(f"wrote {kept} for inspection (NOT printable)")
    if "report" in extra:
        doc = {"unit": "mm", "stats": s.to_dict(), "seconds": seconds,
               "tile_size": shell.tile_size, "shell": shell.name,
               "tiles": tiles.name, "distortion": shell.distortion,
               "coverage": shell.polycube.diagnostics.coverage, "check": rep.to_dict()}
        with atomic_output(extra["report"], "w") as fh:
            json.dump(doc, fh, indent=2, sort_keys=True)
        print(f"wrote {extra['report']}")
    if "picture" in extra:
        from geotex.render import Panel, render_panels

        verdict = "printable" if status == EXIT_OK else "NOT printable"
        render_panels([Panel(V, F, color="#c9b38f",
                             title=f"{tiles.name} on {shell.name}: {len(F)} faces, {verdict}")],
                      extra["picture"], size=(1000, 900), up=args.up)
        print(f"wrote {extra['picture']}")
    return status


def run_map(args) -> int:
    import numpy as np

    from geotex.shells import shell_path
    from geotex.tiles.catalog import load_named as load_tiles, tileset_path

    # the files are named before the polycube machinery loads (geotex.shells' other names)
    tiles_file, shell_file = tileset_path(args.tiles), shell_path(args.shell)
    out, extra = _check_outputs(args, tiles_file, shell_file)
    preload_compiled(three_mf=out.suffix.lower() == ".3mf")      # (the inputs are .npz)
    from geotex.shells import bare_warning, load_named as load_shell, scaled_shell

    tiles, shell = load_tiles(args.tiles), load_shell(args.shell)
    if args.size_mm is not None:
        shell = scaled_shell(shell, args.size_mm / float(np.ptp(shell.base_vertices,
                                                                 axis=0).max()))
    warning = bare_warning(shell, "rebuild the shell with smaller tiles ('geotex shell build "
                                  "BASE --tile-size SIZE')")
    if warning:
        print(warning, file=sys.stderr)
    return _finish(args, shell, tiles, out, extra, label=f"{tiles.name} on {shell.name}")


def run_texture(args) -> int:
    import time

    from geotex.cli.shell import shell_of_file
    from geotex.shells import save_shell
    from geotex.tiles.catalog import load_named as load_tiles, tileset_path

    tiles_file = tileset_path(args.tiles)
    out, extra = _check_outputs(args, args.base, tiles_file)
    preload_compiled(three_mf=".3mf" in (out.suffix.lower(), Path(args.base).suffix.lower()))
    tiles = load_tiles(args.tiles)
    name = Path(args.base).stem
    t = time.perf_counter()
    shell = shell_of_file(args.base, args.tile_size, name=name, size_mm=args.size_mm)
    seconds = {"read+shell": round(time.perf_counter() - t, 3)}
    ts = shell.tile_size
    d = shell.distortion
    search = shell.polycube.diagnostics.tile_search
    auto = (f" (chosen after {len(search.get('attempts', []))} attempts)"
            if search.get("automatic") else "")
    print(f"{args.base}: {shell.n_quads} tiles of {ts:.4g} mm{auto}, safe height "
          f"{shell.max_height:.4g} mm, distortion area {d['area_mean']:.3f} "
          f"angle {d['angle_mean']:.3f}")
    if "shell_out" in extra:
        save_shell(extra["shell_out"], shell)
        print(f"wrote {extra['shell_out']}")
    return _finish(args, shell, tiles, out, extra, label=f"{tiles.name} on {name}",
                   seconds=seconds)
