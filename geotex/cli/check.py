"""``geotex check FILE [--json]``: the validity report of a mesh file."""

from __future__ import annotations

from geotex.cli._common import EXIT_NOT_PRINTABLE, EXIT_OK

HELP = "report whether a mesh file is a printable solid, and why not"


def register(sub):
    p = sub.add_parser("check", help=HELP, description=HELP + ". Exit status: 0 printable, "
                       "1 readable but not printable, 2 unreadable file or bad usage.")
    p.add_argument("file", help="mesh file (.stl .obj .ply .off .3mf .glb)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--no-self-intersections", action="store_true",
                   help="skip the self-intersection test (faster; never 'printable')")
    p.set_defaults(run=run)


def run(args) -> int:
    from geotex.check import check_mesh
    from geotex.check.report import CHECK_STAGES
    from geotex.io import read_mesh
    from geotex.progress import stage_bar

    mesh = read_mesh(args.file)
    with stage_bar(len(CHECK_STAGES), "geotex check",
                   enabled=None if mesh.n_faces > 100_000 else False) as progress:
        report = check_mesh(mesh.vertices, mesh.faces,
                            self_intersections=not args.no_self_intersections,
                            source=str(args.file), progress=progress)
    if args.json:
        print(report.to_json())
    else:
        print(f"file:                      {args.file}")
        print(report.summary())
    return EXIT_OK if report.printable else EXIT_NOT_PRINTABLE
