"""``geotex convert IN OUT``: convert between mesh file formats."""

from __future__ import annotations

from geotex.cli._common import EXIT_OK, guard_output

HELP = "convert a mesh between STL, OBJ, PLY, OFF, 3MF and GLB"


def register(sub):
    p = sub.add_parser("convert", help=HELP, description=HELP + " (format from the extension).")
    p.add_argument("input", help="mesh file to read")
    p.add_argument("output", help="mesh file to write")
    p.add_argument("--ascii", action="store_true", help="write ASCII STL/PLY instead of binary")
    p.set_defaults(run=run)


def run(args) -> int:
    from geotex.io import read_mesh, write_mesh

    out = guard_output(args.output, args.input)
    from geotex.errors import MeshFileError

    mesh = read_mesh(args.input)
    try:
        write_mesh(out, mesh, binary=not args.ascii)
    except MeshFileError as exc:
        if exc.reason.endswith("write an ASCII STL instead"):
            raise MeshFileError(exc.path, exc.reason + " (--ascii)") from None
        raise
    print(f"wrote {out}: {mesh.n_vertices} vertices, {mesh.n_faces} faces")
    return EXIT_OK
