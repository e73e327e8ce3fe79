"""``geotex map`` and ``geotex texture``: tile sets over shells, as printable solids."""

from __future__ import annotations

import json
import sys
from pathlib import Path

from geotex.cli._common import (EXIT_NOT_PRINTABLE, EXIT_OK, UsageError, flag_error,
                                guard_output)

HELP_MAP = "lay a tile set over a shell and write the printable textured solid"
HELP_TEXTURE = "one shot: build the shell of a base mesh and lay a tile set over it"


def _output_options(p):
    p.add_argument("-o", "--output", required=True,
                   help="solid to write (.stl or .3mf; .obj/.ply/.off also accepted)")
    p.add_argument("--height", type=float, default=None,
                   help="texture height in base units (default: the tiles' own proportions, "
                   "at most the shell's safe height)")
    p.add_argument("--seed", type=int, default=0, help="seed of the tile layout (default 0)")
    p.add_argument("--size-mm", type=float, default=None,
                   help="scale the result so its largest extent is this many millimetres "
                   "(default: keep the base's units)")
    p.add_argument("--picture", default=None, help="also write a picture (.png)")
    p.add_argument("--up", choices=("x", "y", "z"), default="z",
                   help="up axis of the picture (default z; the bundled samples are y-up)")
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
                   help="tile side in base units (default: 1/12 of the largest extent)")
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
    return out, extra


def _finish(args, shell, tiles, out, extra, *, label: str) -> int:
    import numpy as np

    from geotex.errors import NotPrintableError
    from geotex.io.atomic import atomic_output
    from geotex.mapping import MAP_STAGES, textured_solid
    from geotex.printing import export_printable
    from geotex.progress import stage_bar

    from geotex.errors import InputError

    try:
        with stage_bar(len(MAP_STAGES), "map") as bar:
            result = textured_solid(shell, tiles, height=args.height, seed=args.seed,
                                    progress=bar)
    except InputError as exc:
        flags = {"height": "--height", "seed": "--seed"}
        if hasattr(args, "tile_size"):                  # 'geotex texture' builds the shell
            flags["tile size"] = "--tile-size"
        raise flag_error(exc, flags) from None
    V, F, rep = result.vertices, result.faces, result.report
    factor = 1.0
    if args.size_mm is not None:
        factor = args.size_mm / float(np.ptp(V, axis=0).max())
        V = V * factor
    s = result.stats
    print(f"{label}: {s['quads']} quads ({s['bare_quads']} bare), {s['elements']} elements, "
          f"height {s['height']:.4g}, {s['faces']} faces")
    if s["elements_floating"] or s["elements_folded"]:
        print(f"  left out: {s['elements_folded']} elements folded by the shell map, "
              f"{s['elements_floating']} that do not reach the base")
    try:
        export_printable(out, V, F, name=label, report=rep if factor == 1.0 else None)
    except NotPrintableError as exc:
        print(f"geotex: error: {exc}", file=sys.stderr)
        return EXIT_NOT_PRINTABLE
    print(f"wrote {out} (printable)")
    if "report" in extra:
        doc = {"stats": s, "scale_to_output": factor, "shell": shell.name,
               "tiles": tiles.name, "distortion": shell.distortion,
               "coverage": shell.polycube.coverage, "check": rep.to_dict()}
        with atomic_output(extra["report"], "w") as fh:
            json.dump(doc, fh, indent=2, sort_keys=True)
        print(f"wrote {extra['report']}")
    if "picture" in extra:
        from geotex.render import Panel, render_panels

        render_panels([Panel(V, F, color="#c9b38f",
                             title=f"{tiles.name} on {shell.name}: {len(F)} faces")],
                      extra["picture"], size=(1000, 900), up=args.up)
        print(f"wrote {extra['picture']}")
    return EXIT_OK


def run_map(args) -> int:
    from geotex.shells import load_named as load_shell, shell_path
    from geotex.tiles.catalog import load_named as load_tiles, tileset_path

    tiles_file, shell_file = tileset_path(args.tiles), shell_path(args.shell)
    out, extra = _check_outputs(args, tiles_file, shell_file)
    tiles, shell = load_tiles(args.tiles), load_shell(args.shell)
    return _finish(args, shell, tiles, out, extra, label=f"{tiles.name} on {shell.name}")


def run_texture(args) -> int:
    from geotex.cli.shell import shell_of_file
    from geotex.shells import save_shell
    from geotex.tiles.catalog import load_named as load_tiles, tileset_path

    tiles_file = tileset_path(args.tiles)
    out, extra = _check_outputs(args, args.base, tiles_file)
    tiles = load_tiles(args.tiles)
    name = Path(args.base).stem
    shell = shell_of_file(args.base, args.tile_size, name=name)
    ts = shell.tile_size
    d = shell.distortion
    print(f"{args.base}: {shell.n_quads} tiles of {ts:.4g}, safe height "
          f"{shell.max_height:.4g}, distortion area {d['area_mean']:.3f} "
          f"angle {d['angle_mean']:.3f}")
    if "shell_out" in extra:
        save_shell(extra["shell_out"], shell)
        print(f"wrote {extra['shell_out']}")
    return _finish(args, shell, tiles, out, extra, label=f"{tiles.name} on {name}")
