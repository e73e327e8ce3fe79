"""``geotex render FILE -o PNG``: an off-screen picture of a mesh file.

One up-axis rule for every format: glTF/GLB files are y-up (their
specification says so); every other format is drawn with ``--up``, default
z.  An explicit ``--up`` always wins (e.g. for a GLB written z-up).
"""

from __future__ import annotations

import math
from pathlib import Path

from geotex.cli._common import EXIT_OK, UsageError, guard_output

HELP = "render a picture (PNG) of a mesh file, off-screen"

#: Formats whose specification fixes the up axis; every other format is z-up
#: unless ``--up`` says otherwise.
UP_BY_SPEC = {".glb": "y", ".gltf": "y"}


def up_axis_for(path, up: str | None) -> str:
    """Return the up axis a picture or viewer of ``path`` uses.

    Parameters
    ----------
    path : str or os.PathLike
        Mesh file name; only its suffix is used.
    up : {"x", "y", "z"} or None
        The user's ``--up``; None means the format's own convention (y for
        glTF/GLB) and z for formats without one.

    Returns
    -------
    str
        ``"x"``, ``"y"`` or ``"z"``.
    """
    if up is not None:
        return up
    return UP_BY_SPEC.get(Path(path).suffix.lower(), "z")


def parse_closeup(text: str) -> tuple[tuple[float, float, float], float | None]:
    """Parse ``--closeup X,Y,Z[,R]`` into a point and an optional radius.

    Parameters
    ----------
    text : str
        Three or four comma-separated numbers (millimetres).

    Returns
    -------
    point : tuple of float
    radius : float or None

    Raises
    ------
    UsageError
        If the text is not three finite numbers plus an optional positive radius.
    """
    try:
        values = [float(t) for t in text.split(",")]
    except ValueError:
        values = []
    if len(values) not in (3, 4) or not all(math.isfinite(v) for v in values):
        raise UsageError(f"--closeup {text}: give X,Y,Z or X,Y,Z,R (numbers in mm)")
    radius = values[3] if len(values) == 4 else None
    if radius is not None and radius <= 0:
        raise UsageError(f"--closeup {text}: the radius R must be positive")
    return (values[0], values[1], values[2]), radius


def register(sub):
    p = sub.add_parser("render", help=HELP, description=HELP + ".")
    p.add_argument("file", help="mesh file")
    p.add_argument("-o", "--output", required=True, help="PNG file to write")
    p.add_argument("--size", nargs=2, type=int, default=(1200, 900), metavar=("W", "H"),
                   help="picture size in pixels (default 1200 900)")
    p.add_argument("--up", default=None, choices=("x", "y", "z"),
                   help="axis pointing up (default: y for glTF/GLB, as their "
                        "specification says; z for every other format)")
    p.add_argument("--closeup", default=None, metavar="X,Y,Z[,R]",
                   help="detail view of the point X,Y,Z (mm) showing a region of radius "
                        "R around it (default R: 12%% of the model's diagonal)")
    p.add_argument("--no-inset", action="store_true",
                   help="with --closeup: leave out the inset (a small picture of the whole "
                        "model in the lower right corner, the close-up circled in red)")
    p.add_argument("--color", default="#d9c7a3",
                   help="surface colour (name or #rrggbb) of meshes without a texture")
    p.add_argument("--no-texture", action="store_true",
                   help="draw in --color even when the file has a texture (GLB, OBJ+MTL)")
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
    closeup, radius = (None, None) if args.closeup is None else parse_closeup(args.closeup)
    mesh = read_mesh(args.file)
    up = up_axis_for(args.file, args.up)
    highlight = None
    if args.highlight and mesh.n_faces:
        topo = edge_topology(mesh.faces, mesh.n_vertices)
        highlight = {"boundary edges": topo.edges[topo.boundary],
                     "non-manifold edges": topo.edges[topo.non_manifold]}
    textured = (not args.no_texture and mesh.texture is not None and mesh.uv is not None
                and mesh.n_faces > 0)
    title = Path(args.file).name if args.title is None else args.title
    render_mesh(mesh.vertices, mesh.faces, out, size=(w, h), up=up, title=title,
                color=args.color, highlight=highlight, show_edges=args.edges,
                uv=mesh.uv if textured else None,
                uv_faces=mesh.uv_faces if textured else None,
                texture=mesh.texture if textured else None,
                closeup=closeup, closeup_radius=radius, inset=not args.no_inset)
    print(f"wrote {out}" + (" (textured)" if textured else ""))
    return EXIT_OK
