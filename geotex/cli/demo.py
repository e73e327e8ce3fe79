"""``geotex demo``: the main job on bundled meshes, writing real files.

Until the tile pipeline lands, the demo runs the most complete job geotex has:
scale a bundled mesh to print size, check it and export it for printing (STL
and 3MF), and repair a bundled broken mesh into a printable solid, with
pictures of both.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from geotex.cli._common import EXIT_NOT_PRINTABLE, EXIT_OK, UsageError

HELP = "run the main job on bundled meshes and write the results"


def register(sub):
    p = sub.add_parser("demo", help=HELP, description=HELP + ".")
    p.add_argument("-o", "--output-dir", default="geotex-demo",
                   help="folder for the results (default ./geotex-demo)")
    p.add_argument("--size-mm", type=float, default=80.0,
                   help="largest extent of the printed model in millimetres (default 80)")
    p.set_defaults(run=run)


def print_ready(V: np.ndarray, *, size_mm: float, y_up: bool) -> np.ndarray:
    """Return ``V`` rotated to z-up (if y-up), scaled to ``size_mm`` and set on z = 0.

    A y-up model is turned by (x, y, z) -> (-x, z, y), a proper rotation that
    also faces its +z front towards the picture's default camera (-y side).
    """
    P = V[:, [0, 2, 1]] * np.array([-1.0, 1.0, 1.0]) if y_up else V.copy()
    lo, hi = P.min(axis=0), P.max(axis=0)
    P = (P - np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]]))
    return P * (size_mm / float(np.max(hi - lo)))


def run(args) -> int:
    from geotex.check import check_mesh
    from geotex.data import sample_path
    from geotex.io import read_mesh
    from geotex.io.atomic import atomic_output
    from geotex.mesh.topology import edge_topology
    from geotex.printing import export_printable
    from geotex.progress import stage_bar
    from geotex.render import Panel, render_panels
    from geotex.repair import repair_mesh

    out = Path(args.output_dir)
    if out.exists() and not out.is_dir():
        raise UsageError(f"{out}: exists and is not a folder")
    if not (1.0 <= args.size_mm <= 1000.0):
        raise UsageError(f"--size-mm {args.size_mm}: choose a size between 1 and 1000 mm")
    out.mkdir(parents=True, exist_ok=True)
    with stage_bar(6, "geotex demo") as stage:
        stage("read spot")
        spot = read_mesh(sample_path("spot"))
        V = print_ready(spot.vertices, size_mm=args.size_mm, y_up=True)
        stage("check and export spot")
        spot_report = check_mesh(V, spot.faces, source="spot")
        export_printable(out / "spot.stl", V, spot.faces, name="spot", report=spot_report)
        export_printable(out / "spot.3mf", V, spot.faces, name="spot", report=spot_report)
        stage("check teapot")
        teapot = read_mesh(sample_path("teapot-open"))
        before = check_mesh(teapot.vertices, teapot.faces, source="teapot_open.stl")
        stage("repair teapot")
        fixed = repair_mesh(teapot.vertices, teapot.faces)
        if fixed.printable:
            export_printable(out / "teapot_repaired.stl", fixed.vertices, fixed.faces,
                             name="teapot", report=fixed.report)
        stage("render spot")
        topo = edge_topology(teapot.faces, teapot.n_vertices)
        render_panels([Panel(V, spot.faces, title=f"spot, {args.size_mm:g} mm, printable: "
                             f"{'yes' if spot_report.printable else 'no'}")],
                      out / "spot.png", size=(1000, 900))
        stage("render teapot")
        render_panels([
            Panel(teapot.vertices, teapot.faces, title="teapot as read: not printable",
                  highlight={"boundary edges": topo.edges[topo.boundary],
                             "non-manifold edges": topo.edges[topo.non_manifold]}),
            Panel(fixed.vertices, fixed.faces, color="#9cc3a5",
                  title=f"after geotex repair: printable {'yes' if fixed.printable else 'no'}"),
        ], out / "teapot_repair.png", size=(900, 800))
        stage("done")
    summary = {"spot": {"files": ["spot.stl", "spot.3mf", "spot.png"],
                        "report": spot_report.to_dict()},
               "teapot": {"changes": fixed.changes, "before": before.to_dict(),
                          "after": fixed.report.to_dict(),
                          "files": (["teapot_repaired.stl"] if fixed.printable else [])
                          + ["teapot_repair.png"]}}
    with atomic_output(out / "report.json", "w") as fh:
        json.dump(summary, fh, indent=2)

    print(f"spot: {spot.n_faces} faces scaled to {args.size_mm:g} mm, printable: "
          f"{'yes' if spot_report.printable else 'no'}")
    print(f"teapot: printable before repair: {'yes' if before.printable else 'no'} "
          f"({'; '.join(before.reasons)})")
    for c in fixed.changes:
        print(f"  - {c}")
    print(f"teapot: printable after repair: {'yes' if fixed.printable else 'no'}")
    print(f"results in {out}/:")
    for name in sorted(p.name for p in out.iterdir()):
        print(f"  {out / name}")
    ok = spot_report.printable and fixed.printable
    return EXIT_OK if ok else EXIT_NOT_PRINTABLE
