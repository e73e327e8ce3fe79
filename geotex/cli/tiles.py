"""``geotex tiles build | check | tile | list | preview``: geometric Wang tile sets."""

from __future__ import annotations

import sys

from geotex.cli._common import EXIT_NOT_PRINTABLE, EXIT_OK, UsageError, guard_output

HELP = "build, check, preview and lay out geometric Wang tile sets"


def register(sub):
    p = sub.add_parser("tiles", help=HELP, description=HELP + ".")
    ts = p.add_subparsers(dest="tiles_command", metavar="ACTION", required=True,
                          parser_class=type(p))

    b = ts.add_parser("build", help="build a tile set from an exemplar",
                      description="Build a tile set from EXEMPLAR: an exemplar name "
                      "(see 'geotex exemplar --list') or an exemplar file (.npz or mesh).")
    b.add_argument("exemplar", help="exemplar name or file")
    b.add_argument("-o", "--output", required=True, help="tile set file to write (.npz)")
    b.add_argument("--colors", default="2", help="colours per axis class: N or NX,NY,NZ "
                   "(default 2)")
    b.add_argument("--planar", action="store_true", help="only the planar tiles")
    b.add_argument("--isotropic", action="store_true",
                   help="one colour class for all axes: N^4 tiles that cover a closed "
                   "polycube when their group is ignored (use one N in --colors)")
    b.add_argument("--directional", action="store_true",
                   help="a directional set for textures pointing +v (scales): (N+1)^4 "
                   "planar base tiles whose extra colour per class is an empty 'ridge' "
                   "strip; 'geotex map' turns them to follow the polycube axes (down on "
                   "the sides, see --up) and puts ridges where the flow turns")
    b.add_argument("--interior", choices=("quilt", "paste", "periodic"), default="quilt",
                   help="tile interiors: constrained mesh quilting (default), whole "
                   "exemplar elements pasted between the frame's (fast), or periodic: "
                   "tiles cut from the exemplar's own periodic layout (linked chainmail, weave; "
                   "with --isotropic)")
    b.add_argument("--lattice", action="store_true",
                   help="keep the exemplar's lattice (period = its pitch, which must divide "
                   "the tile) in every tile: for regular textures such as knurl")
    b.add_argument("--quilted-source", default="auto", metavar="auto|yes|no|SIDE",
                   help="cut the strips and interiors from a larger texture quilted from "
                   "the exemplar first: yes (a 4 x 4 tile square), SIDE (its side in tile "
                   "units, 2 to 12), no, or auto (the default: only when the exemplar "
                   "offers too few distinct edge strips; never with --lattice)")
    b.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    b.add_argument("--name", help="set name (default: the exemplar's)")
    b.add_argument("--workers", type=int, default=None, metavar="N",
                   help="build the tiles on a local Dask cluster of N processes (0 or 1, "
                   "the default: one after another in this process); the set is "
                   "byte-identical either way")
    b.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="build the tiles on a running Dask scheduler's cluster "
                   "(tcp://host:8786) instead")
    b.set_defaults(run=run_build)

    c = ts.add_parser("check", help="verify that every legal neighbour pair is seamless",
                      description="Compare the open boundaries of every pair of tile sides "
                      "that may meet; exit 1 naming the first offending pair.")
    c.add_argument("tileset", help="tile set file or catalog name")
    c.set_defaults(run=run_check)

    t = ts.add_parser("tile", help="random legal tiling of the plane, as a printable solid",
                      description="Lay out a random legal W x H arrangement, weld it, union "
                      "it with a slab and write a printable solid.")
    t.add_argument("tileset", help="tile set file or catalog name")
    t.add_argument("--grid", nargs=2, type=int, metavar=("W", "H"), required=True)
    t.add_argument("-o", "--output", required=True, help="mesh file (.stl, .3mf, ...)")
    t.add_argument("--seed", type=int, default=0)
    t.add_argument("--slab", type=float, default=0.2, help="slab thickness in tile units")
    t.add_argument("--tile-size", type=float, default=10.0,
                   help="tile edge length in output units (default 10, i.e. mm)")
    t.set_defaults(run=run_tile)

    ls = ts.add_parser("list", help="list the tile set catalog")
    ls.set_defaults(run=run_list)

    v = ts.add_parser("preview", help="picture of a tile set and a random tiling")
    v.add_argument("tileset", help="tile set file or catalog name")
    v.add_argument("-o", "--output", required=True, help="PNG file to write")
    v.add_argument("--grid", type=int, default=6, help="tiling size (default 6)")
    v.add_argument("--seed", type=int, default=0)
    v.set_defaults(run=run_preview)


def _exemplar(spec: str, seed: int):
    from pathlib import Path

    from geotex import exemplars

    if Path(spec).exists():
        return exemplars.load_exemplar(spec)
    if spec in exemplars.EXEMPLAR_KINDS:
        return exemplars.exemplar(spec, seed=seed)
    raise UsageError(f"{spec}: no such file or exemplar name "
                     f"({', '.join(exemplars.EXEMPLAR_KINDS)})")


def _tile_mapper(workers, scheduler):
    """``map_tiles`` for :func:`~geotex.tiles.build.build_tileset` from --workers/--scheduler."""
    if workers is not None and workers < 0:
        raise UsageError(f"--workers {workers}: give a number of workers >= 0")
    if scheduler is not None and workers is not None:
        raise UsageError("--workers and --scheduler exclude each other: the scheduler's "
                         "cluster has its own workers")
    if scheduler is not None and "://" not in scheduler:
        raise UsageError(f"--scheduler {scheduler}: give an address such as "
                         "tcp://host:8786")
    if scheduler is None and (workers is None or workers <= 1):
        return None

    def map_tiles(function, plan, n):
        from geotex.batch.run import map_tasks

        return map_tasks(function, plan, n, workers=workers, scheduler=scheduler,
                         imports=("geotex.tiles.build", "geotex.quilting"))

    return map_tiles


def _quilted_source(text: str):
    """``quilted_source`` of :func:`~geotex.tiles.build.build_tileset` from --quilted-source."""
    word = text.strip().lower()
    if word == "auto":
        return "auto"
    if word in ("yes", "on", "true"):
        return True
    if word in ("no", "off", "false"):
        return False
    from geotex.tiles.source import SIDE_RANGE

    try:
        side = float(word)
    except ValueError:
        raise UsageError(f"--quilted-source {text}: give auto, yes, no or a side in tile "
                         "units") from None
    if not SIDE_RANGE[0] <= side <= SIDE_RANGE[1]:      # NaN fails too
        raise UsageError(f"--quilted-source {text}: a side between {SIDE_RANGE[0]:g} and "
                         f"{SIDE_RANGE[1]:g} tile units")
    return side


def run_build(args) -> int:
    import time

    from geotex.progress import stage_bar
    from geotex.tiles.build import build_tileset
    from geotex.tiles.colors import parse_colors, tile_count
    from geotex.tiles.tileset import save_tileset

    out = guard_output(args.output, args.exemplar)
    if out.suffix.lower() != ".npz":
        raise UsageError(f"{out}: tile sets are written as .npz files")
    map_tiles = _tile_mapper(args.workers, args.scheduler)
    quilted = _quilted_source(args.quilted_source)
    ex = _exemplar(args.exemplar, args.seed)
    n_colors = parse_colors(args.colors, planar=args.planar or args.directional)
    n = ((n_colors[0] + 1) ** 2 * (n_colors[1] + 1) ** 2 if args.directional else
         tile_count(n_colors, planar=args.planar, isotropic=args.isotropic))
    start = time.perf_counter()
    with stage_bar(1 + n, f"tiles ({n})") as bar:
        tiles = build_tileset(ex, colors=args.colors, planar=args.planar,
                              isotropic=args.isotropic, lattice=args.lattice,
                              interior=args.interior, directional=args.directional,
                              seed=args.seed, name=args.name, quilted_source=quilted,
                              progress=bar, map_tiles=map_tiles)
    elapsed = time.perf_counter() - start
    save_tileset(out, tiles)
    extra = ""
    if tiles.metadata.get("quilted_source"):
        q = tiles.metadata["quilted_source"]
        extra += (f", strips cut from a {q['side']:g} x {q['side']:g} texture quilted from "
                  f"the exemplar ({q['elements']} elements)")
    if tiles.metadata.get("paste_fallbacks"):
        extra += f", {tiles.metadata['paste_fallbacks']} tiles pasted after quilting failed"
    print(f"{out}: {tiles.kind} set, {len(tiles)} tiles, colours X/Y/Z {tiles.n_colors}, "
          f"height {tiles.height:.3g}, coverage {tiles.metadata['coverage_mean']:.0%}{extra}, "
          f"{elapsed:.2f} s ({1000 * elapsed / len(tiles):.0f} ms per tile)")
    return EXIT_OK


def run_check(args) -> int:
    from geotex.tiles.catalog import load_named
    from geotex.tiles.verify import check_seams

    tiles = load_named(args.tileset)
    rep = check_seams(tiles)
    if rep.ok:
        print(f"{args.tileset}: seamless: {len(tiles)} tiles, {rep.pairs_checked} side "
              "pairs checked")
        return EXIT_OK
    print(f"geotex: error: {args.tileset}: {rep.problems[0]} "
          f"({len(rep.problems)} problems)", file=sys.stderr)
    return EXIT_NOT_PRINTABLE


def run_tile(args) -> int:
    from geotex.errors import NotPrintableError
    from geotex.printing import export_printable, printable_stored_solid, stored_precision
    from geotex.tiles.catalog import load_named, tileset_path
    from geotex.tiles.tiling import on_slab, planar_tiling, random_arrangement

    out = guard_output(args.output, tileset_path(args.tileset))
    if args.slab <= 0 or args.tile_size <= 0:
        raise UsageError("--slab and --tile-size must be positive")
    tiles = load_named(args.tileset)
    w, h = args.grid
    arrangement = random_arrangement(tiles, w, h, seed=args.seed)
    V, F = on_slab(*planar_tiling(tiles, arrangement), (w, h), thickness=args.slab)
    # judged as the file stores it, what the rounding breaks rebuilt (as the main job does)
    solid = printable_stored_solid(V * args.tile_size, F, precision=stored_precision(out.suffix))
    try:
        export_printable(out, solid.vertices, solid.faces, name=f"{tiles.name} {w}x{h}",
                         report=solid.report)
    except NotPrintableError as exc:
        print(f"geotex: error: {exc}", file=sys.stderr)
        return EXIT_NOT_PRINTABLE
    print(f"{out}: {len(solid.faces)} faces, {w} x {h} tiles of {args.tile_size:g}, printable")
    return EXIT_OK


def run_list(args) -> int:
    from geotex.tiles.catalog import list_tilesets

    rows = list_tilesets()
    if not rows:
        print("the tile catalog is empty")
        return EXIT_OK
    print(f"{'name':<16}{'kind':<11}{'tiles':>6}  {'colours':<9}{'size':>8}  "
          f"{'exemplar':<10} description")
    for r in rows:
        cols = ",".join(str(c) for c in r["colors"])
        print(f"{r['name']:<16}{r['kind']:<11}{r['tiles']:>6}  {cols:<9}"
              f"{r['bytes'] / 1e6:>6.2f}MB  {r['exemplar']:<10} {r['description']}")
    return EXIT_OK


def run_preview(args) -> int:
    from geotex.tiles.catalog import load_named, tileset_path
    from geotex.tiles.preview import render_tileset

    out = guard_output(args.output, tileset_path(args.tileset))
    if out.suffix.lower() != ".png":
        raise UsageError(f"{out}: previews are PNG pictures")
    render_tileset(load_named(args.tileset), out, grid=args.grid, seed=args.seed)
    print(f"{out}: preview written")
    return EXIT_OK
