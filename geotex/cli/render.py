"""``geotex render FILE -o PNG``: an off-screen picture of a mesh file."""

from __future__ import annotations

from pathlib import Path

from geotex.cli._common import EXIT_OK, UsageError, guard_output

HELP = "render a picture (PNG) of a mesh file, off-screen"

#: Default up axis by file type: OBJ/PLY/OFF/GLB are usually y-up, print files z-up.
UP_BY_SUFFIX = {".obj": "y", ".ply": "y", ".off": "y", ".glb": "y", ".stl": "z", ".3mf": "z"}


def register(sub):
    p = sub.add_parser("render", help=HELP, description=HELP + ".")
    p.add_argument("file", help="mesh file")
    p.add_argument("-o", "--output", required=True, help="PNG file to write")
    p.add_argument("--size", nargs=2, type=int, default=(1200, 900), metavar=("W", "H"),
                   help="picture size in pixels (default 1200 900)")
    p.add_argument("--up", default="auto", choices=("auto", "x", "y", "z"),
                   help="axis pointing up (default: y for OBJ/PLY/OFF/GLB, z for STL/3MF)")
    p.add_argument("--color", default="#d9c7a3", help="surface colour (name or #rrggbb)")
    p.add_argument("--edges", action="store_true", help="draw the triangle wireframe")
    p.add_argument("--highlight", action="store_true",
                   help="draw boundary and non-manifold edges in colour")
    p.add_argument("--title", default=None, help="caption (default: the file name)")
    p.set_defaults(run=run)


def run(args) -> int:
    from geotex.io import read_mesh
    from geotex.mesh.topology import edge_topology
    from geotex.render import render_mesh

    out = guard_output(args.output, args.file)
    if out.suffix.lower() != ".png":
        raise UsageError(f"{out}: pictures are written as PNG; use a .png file name")
    w, h = args.size
    if not (16 <= w <= 8192 and 16 <= h <= 8192):
        raise UsageError(f"--size {w} {h}: width and height must be between 16 and 8192")
    mesh = read_mesh(args.file)
    up = UP_BY_SUFFIX.get(Path(args.file).suffix.lower(), "z") if args.up == "auto" else args.up
    highlight = None
    if args.highlight and mesh.n_faces:
        topo = edge_topology(mesh.faces, mesh.n_vertices)
        highlight = {"boundary edges": topo.edges[topo.boundary],
                     "non-manifold edges": topo.edges[topo.non_manifold]}
    title = Path(args.file).name if args.title is None else args.title
    render_mesh(mesh.vertices, mesh.faces, out, size=(w, h), up=up, title=title,
                color=args.color, highlight=highlight, show_edges=args.edges)
    print(f"wrote {out}")
    return EXIT_OK
