"""
Check, repair and export for printing, with pictures
====================================================

Reads the bundled Spot and the bundled open teapot, prints their validity
reports, repairs the teapot, exports both as printable 3MF, and draws the
problems geotex found (boundary edges in red, non-manifold edges in orange)
beside the repaired result.

Run:  python examples/check_and_repair.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import sys
from pathlib import Path

from geotex.check import check_mesh
from geotex.data import sample_path
from geotex.io import read_mesh, write_mesh
from geotex.mesh import Mesh
from geotex.mesh.topology import edge_topology
from geotex.printing import export_printable
from geotex.render import Panel, render_panels
from geotex.repair import repair_mesh
from geotex.viewpage import mesh_turned_y_up


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    spot = read_mesh(sample_path("spot"))
    report = check_mesh(spot.vertices, spot.faces)
    print("spot:\n" + report.summary())
    export_printable(out / "spot.3mf", spot.vertices * 50.0, spot.faces)
    write_mesh(out / "spot.glb", Mesh(spot.vertices * 50.0, spot.faces))   # Spot is y-up

    teapot = read_mesh(sample_path("teapot-open"))
    before = check_mesh(teapot.vertices, teapot.faces)
    print("\nteapot before repair:\n" + before.summary())
    fixed = repair_mesh(teapot.vertices, teapot.faces)
    print("\nrepair: " + "; ".join(fixed.changes))
    print("teapot after repair:\n" + fixed.report.summary())
    export_printable(out / "teapot_repaired.3mf", fixed.vertices, fixed.faces)
    # the 3D viewer's copy, y-up as glTF specifies (the teapot is z-up)
    write_mesh(out / "teapot_repaired.glb",
               mesh_turned_y_up(Mesh(fixed.vertices, fixed.faces), up="z"))

    topo = edge_topology(teapot.faces, teapot.n_vertices)
    render_panels([
        Panel(spot.vertices[:, [0, 2, 1]] * [-1, 1, 1], spot.faces,
              title=f"Spot: printable {'yes' if report.printable else 'no'}, "
                    f"genus {report.genus}"),
        Panel(teapot.vertices, teapot.faces, title="teapot as read: not printable",
              highlight={"boundary edges": topo.edges[topo.boundary],
                         "non-manifold edges": topo.edges[topo.non_manifold]}),
        Panel(fixed.vertices, fixed.faces, color="#9cc3a5",
              title="after repair_mesh: printable "
                    f"{'yes' if fixed.printable else 'no'}"),
    ], out / "check_and_repair.png", size=(700, 600))
    print(f"\nwrote {out / 'check_and_repair.png'}, {out / 'spot.3mf'}, "
          f"{out / 'teapot_repaired.3mf'}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
