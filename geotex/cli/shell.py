"""``geotex shell build | list | show``: polycube shells over base meshes."""

from __future__ import annotations

import sys

from geotex.cli._common import EXIT_OK, UsageError, flag_error, guard_output, preload_compiled

HELP = "build, list and show shells (base mesh + polycube parameterization)"


def register(sub):
    p = sub.add_parser("shell", help=HELP, description=HELP + ".")
    ss = p.add_subparsers(dest="shell_command", metavar="ACTION", required=True,
                          parser_class=type(p))

    b = ss.add_parser("build", help="parameterize a closed base mesh by a polycube",
                      description="Build the shell of BASE: a voxel polycube whose grid "
                      "quads are tiles of side --tile-size, fitted onto BASE, with offset "
                      "directions and the largest safe texture height.")
    b.add_argument("base", help="closed base mesh file (run 'geotex repair' first if needed)")
    b.add_argument("-o", "--output", required=True, help="shell file to write (.npz)")
    b.add_argument("--tile-size", type=float, default=None,
                   help="tile side in mesh units (default: automatic, the largest size from 1/12 "
                   "of the largest extent down that resolves and covers the shape)")
    b.add_argument("--name", default=None, help="shell name (default: the file stem)")
    b.set_defaults(run=run_build)

    ls = ss.add_parser("list", help="the catalog of ready shells",
                       description="List the shells shipped with geotex.")
    ls.set_defaults(run=run_list)

    s = ss.add_parser("show", help="picture of a shell's polycube",
                      description="Render SHELL (file or catalog name): base coloured by chart "
                      "label, the polycube, and the base with the quad grid.")
    s.add_argument("shell", help="shell file or catalog name")
    s.add_argument("-o", "--output", required=True, help="PNG file to write")
    s.set_defaults(run=run_show)


def _describe(shell) -> str:
    d = shell.distortion
    pc = shell.polycube
    folded = int(pc.quad_folded.sum())
    search, cover = pc.diagnostics.tile_search, pc.diagnostics.coverage
    chosen = (f" (chosen after {len(search.get('attempts', []))} attempts)"
              if search.get("automatic") else "")
    return (f"{shell.n_quads} quads of {shell.tile_size:.4g}{chosen}"
            + (f" ({folded} folded, left bare)" if folded else "")
            + f", max height {shell.max_height:.4g}; "
            f"distortion area {d['area_mean']:.3f} (p95 {d['area_p95']:.3f}), "
            f"angle {d['angle_mean']:.3f} (p95 {d['angle_p95']:.3f}); "
            f"{100 * cover.get('within_tile', 1.0):.1f}% of the base within a tile, "
            f"{100 * cover.get('within_quarter_tile', 1.0):.1f}% within a quarter tile")


def shell_of_file(base, tile_size, *, name: str, size_mm=None):
    """Build the shell of a mesh file; the tile size is chosen when it is None.

    With ``size_mm`` the base is first scaled so its largest extent is that
    many millimetres, and ``tile_size`` is in millimetres at that size.
    """
    from pathlib import Path

    import numpy as np

    from geotex.errors import GeotexError
    from geotex.io import read_mesh
    from geotex.progress import stage_bar
    from geotex.shells import SHELL_STAGES, bare_warning, build_shell

    mesh = read_mesh(base)
    if size_mm is not None and mesh.n_vertices:
        ext = float(np.ptp(mesh.vertices, axis=0).max())
        if ext > 0:
            mesh = mesh.with_geometry(mesh.vertices * (size_mm / ext), mesh.faces)
    if tile_size is not None and not tile_size > 0:
        raise UsageError(f"--tile-size {tile_size}: give a positive number")
    from geotex.errors import InputError

    with stage_bar(len(SHELL_STAGES), "shell") as bar:
        try:
            shell = build_shell(mesh.vertices, mesh.faces, tile_size=tile_size, name=name,
                                source=Path(base).name, recipe={"source": Path(base).name},
                                progress=bar)
        except InputError as exc:
            raise flag_error(exc, {"tile size": "--tile-size"}) from None
        except GeotexError as exc:
            if tile_size is None or type(exc) is not GeotexError:
                raise
            raise GeotexError(f"--tile-size {tile_size:g}: {exc} (or leave --tile-size out "
                              "to choose it automatically)") from None
    warning = bare_warning(shell, "use a smaller --tile-size" + (
        " (or leave it out to choose one that covers the base)" if tile_size is not None
        else " (the automatic size covers the base within a tile, not this)"))
    if warning:
        print(warning, file=sys.stderr)
    shell.recipe["tile_size"] = shell.tile_size
    if size_mm is not None:
        shell.recipe["size_mm"] = size_mm
    if tile_size is None:
        shell.recipe["tile_size_automatic"] = True
    return shell


def run_build(args) -> int:
    from pathlib import Path

    from geotex.shells import save_shell

    out = guard_output(args.output, args.base)
    if not str(out).lower().endswith(".npz"):
        raise UsageError(f"{out}: shell files are .npz; use a .npz name for -o")
    preload_compiled()
    shell = shell_of_file(args.base, args.tile_size, name=args.name or Path(args.base).stem)
    save_shell(out, shell)
    print(f"{args.base}: {_describe(shell)}")
    print(f"wrote {out}")
    return EXIT_OK


def run_list(args) -> int:
    from geotex.shells import list_shells

    rows = list_shells()
    if not rows:
        print("the shell catalog is empty")
        return EXIT_OK
    print(f"{'name':<8} {'faces':>6} {'tile':>7} {'quads':>6} {'max h':>7} "
          f"{'area':>6} {'angle':>6}  source")
    for r in rows:
        d = r.get("distortion", {})
        print(f"{r['name']:<8} {r.get('base_faces', 0):>6} {r.get('tile_size', 0):>7.4g} "
              f"{r.get('quads', 0):>6} {r.get('max_height', 0):>7.4g} "
              f"{d.get('area_mean', float('nan')):>6.3f} {d.get('angle_mean', float('nan')):>6.3f}"
              f"  {r['recipe'].get('source', '')}")
    return EXIT_OK


def run_show(args) -> int:
    from geotex.shells import load_named, shell_path
    from geotex.shells.picture import shell_panels
    from geotex.render import render_panels

    src = shell_path(args.shell)
    out = guard_output(args.output, src)
    if not str(out).lower().endswith(".png"):
        raise UsageError(f"{out}: pictures are PNG; use a .png name for -o")
    shell = load_named(args.shell)
    render_panels(shell_panels(shell), out, size=(600, 600))
    print(f"{shell.name}: {_describe(shell)}")
    print(f"wrote {out}")
    return EXIT_OK
