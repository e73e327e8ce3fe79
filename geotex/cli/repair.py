"""``geotex repair IN -o OUT``: repair a mesh towards a printable solid."""

from __future__ import annotations

import json
import sys

from geotex.cli._common import EXIT_NOT_PRINTABLE, EXIT_OK, guard_output

HELP = "weld, clean, orient, fill holes and resolve self-intersections"


def register(sub):
    p = sub.add_parser("repair", help=HELP, description=HELP + ". Exit status: 0 when the "
                       "result is printable, 1 when it is not, or when cutting "
                       "self-intersections changed the number of shells or lost more than "
                       "1%% of the volume (nothing is written unless --force), 2 on "
                       "unreadable input or bad usage.")
    p.add_argument("input", help="mesh file to repair (never overwritten)")
    p.add_argument("-o", "--output", required=True, help="repaired mesh file")
    p.add_argument("--weld-tolerance", type=float, default=None,
                   help="merge distance (default 1e-6 x bounding-box diagonal)")
    p.add_argument("--max-hole-edges", type=int, default=None,
                   help="largest hole to close, in boundary edges (default: all)")
    p.add_argument("--no-fill-holes", action="store_true", help="leave holes open")
    p.add_argument("--keep-intersections", action="store_true",
                   help="do not try to resolve self-intersections")
    p.add_argument("--force", action="store_true",
                   help="write the result even if it is still not printable or the repair "
                        "changed the solid")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=run)


def run(args) -> int:
    from geotex.check import check_mesh
    from geotex.errors import NotPrintableError
    from geotex.io import read_mesh, write_mesh
    from geotex.printing import PRINT_FORMATS, export_printable
    from geotex.progress import stage_bar
    from geotex.repair import REPAIR_STAGES, repair_mesh

    out = guard_output(args.output, args.input)
    mesh = read_mesh(args.input)
    before = check_mesh(mesh.vertices, mesh.faces)
    with stage_bar(len(REPAIR_STAGES), "geotex repair",
                   enabled=None if mesh.n_faces > 100_000 else False) as progress:
        result = repair_mesh(mesh.vertices, mesh.faces, weld_tolerance=args.weld_tolerance,
                             fill_holes=not args.no_fill_holes,
                             max_hole_edges=args.max_hole_edges,
                             resolve_intersections=not args.keep_intersections,
                             progress=progress)
    report = result.report
    accepted = report.printable and result.faithful
    written = False
    if (accepted or args.force) and out.suffix.lower() in PRINT_FORMATS:
        # judged again as the file stores it (float32 for STL), read back
        try:
            report = export_printable(out, result.vertices, result.faces, force=args.force,
                                      name=mesh.name or out.stem)
            written = True
        except NotPrintableError as exc:
            report = exc.report
    elif accepted or args.force:
        write_mesh(out, mesh.with_geometry(result.vertices, result.faces))
        written = True
    if args.json:
        print(json.dumps({"input": str(args.input), "output": str(out) if written else None,
                          "changes": result.changes, "printable_before": before.printable,
                          "printable": report.printable, "reasons": report.reasons,
                          "warnings": result.warnings,
                          "report": report.to_dict()}))
    else:
        print(f"{args.input}: {before.vertices} vertices, {before.faces} faces, "
              f"printable before: {'yes' if before.printable else 'no'}")
        for c in result.changes or ["nothing to change"]:
            print(f"  - {c}")
        print(f"result: {report.vertices} vertices, {report.faces} faces")
        print(f"printable: {'yes' if report.printable else 'no'}")
        for r in report.reasons:
            print(f"  - {r}")
        for w in result.warnings:
            print(f"warning: {w}")
        if written:
            print(f"wrote {out}")
    if not written:
        why = ("not printable as stored" if not report.printable and result.report.printable
               else "still not printable" if not report.printable
               else f"the repair changed the solid: {'; '.join(result.warnings)}")
        print(f"geotex: not written: {out} ({why}; use --force to write it)", file=sys.stderr)
    if not report.printable:
        return EXIT_NOT_PRINTABLE
    return EXIT_OK if accepted or args.force else EXIT_NOT_PRINTABLE
