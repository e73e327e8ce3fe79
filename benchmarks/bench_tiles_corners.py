"""Benchmark: are the tile corners filled? Relief density at tile corners, per catalog set.

For every set of the tile catalog, a random legal 6 x 6 arrangement (seed 0,
the arrangement ``geotex tiles tile --grid 6 6`` writes) is laid out and
welded, and :func:`geotex.tiles.verify.corner_density` compares the projected
area of the faces above the tile plane within a quarter tile of a tile corner
with the rest (issue 14 target: corner density at least 0.85 of the density
elsewhere). Each set is also checked seamless (``check_seams``), and the seams
stitched inside the tiles by the quilting engine are summarised from the set's
metadata (largest loop gap before stitching relative to the quilting cell,
mean and largest normal jump across the stitch strips, degrees). Sides of
neighbouring tiles weld by exact position (``check_seams`` compares them bit
for bit): their gap is 0 by construction.

With ``--baseline DIR`` the same measure is taken on the ``NAME.npz`` files of
DIR (e.g. the catalog of an earlier commit, extracted with ``git show``) and
shown as "before".

The results file's section from the heading "## Notes" on is hand-written and
kept when the table is written again.

Run:  python benchmarks/bench_tiles_corners.py [--baseline DIR [--baseline-label TEXT]]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
from pathlib import Path

import numpy as np

from geotex.mesh.geometry import face_normals
from geotex.mesh.topology import edge_topology
from geotex.tiles import list_tilesets, load_named, load_tileset
from geotex.tiles.tiling import planar_tiling, random_arrangement
from geotex.tiles.verify import check_seams, corner_density

RESULTS = Path(__file__).parent / "results"
TARGET = 0.85
NOTES = "## Notes"      # from this heading on, results/tiles_corners.md is hand-written


def side_seams(V, F, grid) -> dict:
    """Seams across the inner tile sides of a welded planar tiling.

    Edges lying on an inner grid line (both ends at the same whole ``u`` in
    ``1 .. W-1``, or ``v``), where an element crosses from one tile into the
    next: ``open`` counts those with one face only (a gap: the sides did not
    weld), ``jump_mean`` / ``jump_max`` the angle (degrees) between the two
    faces of the welded ones, one in each tile.
    """
    topo = edge_topology(F, len(V))
    E = topo.edges
    P, Q = V[E[:, 0]], V[E[:, 1]]
    on = np.zeros(len(E), dtype=bool)
    for axis, n in ((0, grid[0]), (1, grid[1])):
        line = (P[:, axis] == Q[:, axis]) & (P[:, axis] == np.round(P[:, axis]))
        on |= line & (P[:, axis] >= 1) & (P[:, axis] <= n - 1)
    two = on & (topo.face_count == 2)
    ef = topo.edge_faces()[two]
    N = face_normals(V, F)
    ang = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", N[ef[:, 0]], N[ef[:, 1]]),
                                       -1.0, 1.0)))
    return {"edges": int(two.sum()), "open": int((on & (topo.face_count == 1)).sum()),
            "jump_mean": round(float(ang.mean()), 3) if ang.size else None,
            "jump_max": round(float(ang.max()), 3) if ang.size else None}


def measure(tiles) -> dict:
    """Corner density figures and tile-side seams of one tile set on a 6 x 6 tiling."""
    V, F = planar_tiling(tiles, random_arrangement(tiles, 6, 6, seed=0), border="open")
    d = corner_density(V, F, (6, 6))
    return {"corner": round(d.corner, 4), "elsewhere": round(d.elsewhere, 4),
            "ratio": round(d.ratio, 4), "sides": side_seams(V, F, (6, 6))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--baseline", type=Path, help="directory of earlier NAME.npz files")
    ap.add_argument("--baseline-label", default="",
                    help="what the baseline files are (one sentence for the results)")
    args = ap.parse_args()
    rows = []
    for entry in list_tilesets():
        name = entry["name"]
        tiles = load_named(name)
        seams = check_seams(tiles)
        meta = tiles.metadata
        row = {"name": name, "kind": tiles.kind, "tiles": len(tiles),
               "bytes": entry["bytes"], "seamless": seams.ok,
               "after": measure(tiles),
               "stitched_seams": meta.get("stitched_seams", 0),
               "seam_gap_max": meta.get("seam_gap_max"),
               "seam_normal_jump_mean": meta.get("seam_normal_jump_mean"),
               "seam_normal_jump_max": meta.get("seam_normal_jump_max")}
        if args.baseline is not None and (args.baseline / f"{name}.npz").is_file():
            row["before"] = measure(load_tileset(args.baseline / f"{name}.npz"))
        rows.append(row)
        print(name, row["after"], row.get("before"), flush=True)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "tiles_corners.json").write_text(json.dumps(
        {"target_ratio": TARGET, "grid": [6, 6], "seed": 0, "sets": rows}, indent=1) + "\n")

    def fmt(x, spec=".2f"):
        return "-" if x is None or (isinstance(x, float) and not np.isfinite(x)) else \
            format(x, spec)

    lines = [
        "# Benchmark: relief density at tile corners",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores (shared), Python "
        f"{platform.python_version()}, numpy {np.__version__}. Script: "
        "`benchmarks/bench_tiles_corners.py`.",
        "",
        "Every catalog set, random legal 6 x 6 arrangement (seed 0, the one `geotex tiles "
        "tile --grid 6 6` writes), welded; `corner_density` rasterizes the faces above the "
        "tile plane (1/40 tile pixels) and compares the covered fraction of the corner "
        "squares (within a quarter tile of a tile corner) with the rest. Target (issue 14): "
        f"ratio at least {TARGET}." + (f" Before: {args.baseline_label}"
                                       if args.baseline_label else ""),
        "",
        "| set | kind | tiles | MB | seamless | corner / elsewhere before | ratio before "
        "| corner / elsewhere after | ratio after | stitched seams | seam gap max | "
        "normal jump mean / max (deg) | side seam edges (open) | side normal jump "
        "mean / max (deg) |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        b, a = r.get("before"), r["after"]
        lines.append(
            f"| {r['name']} | {r['kind']} | {r['tiles']} | {r['bytes'] / 1e6:.2f} | "
            f"{'yes' if r['seamless'] else 'NO'} | "
            + (f"{b['corner']:.3f} / {b['elsewhere']:.3f} | {b['ratio']:.2f} | " if b else
               "- | - | ")
            + f"{a['corner']:.3f} / {a['elsewhere']:.3f} | {a['ratio']:.2f} | "
            f"{r['stitched_seams']} | {fmt(r['seam_gap_max'], '.3f')} | "
            f"{fmt(r['seam_normal_jump_mean'], '.1f')} / "
            f"{fmt(r['seam_normal_jump_max'], '.1f')} | "
            f"{a['sides']['edges']} ({a['sides']['open']}) | "
            f"{fmt(a['sides']['jump_mean'], '.2f')} / {fmt(a['sides']['jump_max'], '.1f')} |")
    lines += [
        "",
        "Seam columns: joins stitched inside the tiles by the quilting engine when a "
        "copy merges with a frame or interior element (largest loop-to-loop distance "
        "before the stitch relative to the quilting cell; angle between the faces on "
        "either side of a stitch strip, mean over merges of each merge's largest angle). "
        "They count merges that the tile builder later undid (a merge that fused two "
        "different elements is reverted), so they describe the engine, not only what "
        "ships. Tile sides weld by exact position: gap 0, checked bit for bit by "
        "`check_seams`. Side seam columns: the edges of the welded 6 x 6 tiling on the "
        "inner tile lines, where elements cross from one tile into the next (in brackets "
        "those left open, i.e. not welded), and the angle between the two faces of each "
        "(one in each tile): an element cut by a side keeps its own surface across it, "
        "so the angle is that of the element's own faces there (0 where the cut split a "
        "face).",
        "",
    ]
    md = RESULTS / "tiles_corners.md"
    kept = ""
    if md.is_file():
        old = md.read_text()
        if "\n" + NOTES in old:            # hand-written notes stay below the table
            kept = old[old.index("\n" + NOTES) + 1:]
    md.write_text("\n".join(lines) + ("\n" + kept if kept else ""))


if __name__ == "__main__":
    main()
