"""``geotex view FILE``: an offline HTML page with an interactive 3D viewer.

The page (``FILE.html`` next to the file unless ``-o`` says otherwise) embeds
the three.js viewer and the model as a base64 GLB, so it opens from the file
system with no server.  The up axis follows ``geotex render``: glTF/GLB is
y-up, every other format ``--up`` (default z).
"""

from __future__ import annotations

from pathlib import Path

from geotex.cli._common import EXIT_OK, UsageError, guard_output

HELP = "write an offline HTML page with an interactive 3D viewer of a mesh file"


def register(sub):
    p = sub.add_parser("view", help=HELP, description=HELP + " (no server needed).")
    p.add_argument("file", help="mesh file")
    p.add_argument("-o", "--output", default=None,
                   help="HTML file to write (default: FILE.html next to the file)")
    p.add_argument("--up", default=None, choices=("x", "y", "z"),
                   help="axis pointing up (default: y for glTF/GLB, as their "
                        "specification says; z for every other format)")
    p.add_argument("--title", default=None, help="page title (default: the file name)")
    p.set_defaults(run=run)


def run(args) -> int:
    from geotex.cli.render import up_axis_for
    from geotex.io import read_mesh
    from geotex.viewpage import viewer_bundle, write_viewer_page

    src = Path(args.file)
    out = Path(args.output) if args.output else src.with_name(src.name + ".html")
    out = guard_output(out, args.file)
    if out.suffix.lower() not in (".html", ".htm"):
        raise UsageError(f"{out}: viewer pages are HTML; use a .html file name")
    viewer_bundle()                      # fail before reading a large file
    mesh = read_mesh(args.file)
    if mesh.n_faces == 0:
        raise UsageError(f"{args.file}: has no triangles to show")
    up = up_axis_for(args.file, args.up)
    write_viewer_page(mesh, out, title=args.title or src.name, up=up)
    textured = mesh.texture is not None and mesh.uv is not None
    print(f"wrote {out} ({mesh.n_faces} triangles{', textured' if textured else ''}); "
          "open it in a web browser")
    return EXIT_OK
