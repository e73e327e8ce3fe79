"""Benchmark: do elements keep their shape on objects? (issue 14, item 5)

For the ``studs`` set on the catalog shells (spot, bob, torus, blub), seed 0:

* element footprints (:func:`geotex.mapping.shape.element_footprints`: every
  mapped element projected onto its tangent plane, the offset direction
  averaged over its points): coefficient of variation (CV) of the footprint
  areas and the elongation ``sqrt(l1/l2)`` of their second moments (mean,
  95th percentile, max), against the same figures on the planar 6 x 6 tiling
  (``random_arrangement(..., 6, 6, seed=0)``, projected along z). Target: CV on
  the object at most 1.5 x the planar CV. Measured twice: on the elements
  as ``mapped_tiles`` lays them (before the job re-seats the folded ones)
  and on the elements as ``textured_solid`` ends them
  (``keep_elements=True``: re-seated and rooted, the ones left out excluded
  and counted);
* bare quads (no tile: their map folds), faces of open elements dropped, and
  elements left out (folded by the shell map, floating above the base, next
  to defects) or re-seated (shrunk in place), from the full job
  ``textured_solid`` with its check; whether the result is printable;
* seconds of the map stage (``stats.seconds["map"]``, and the CPU seconds of
  ``mapped_tiles``, best of 3) and of the whole job; the machine is shared, so
  the wall times are indicative.

Each shell is run twice: ``plain`` maps every tile point through the quad map
(what main did before), ``shaped`` maps every small element as one shape
(``textured_solid(..., shaped=True)``, the default).

Main-job rows (``spot 15k``, ``kitten 15k``, ``bob 15k``; shaped only): the
shells ``geotex texture BASE --tiles studs --size-mm 80`` builds on the
~15k-face decimations of ``bench_main_job.py`` (the first thing a new user
sees; ``--data`` points at the shared data folder, ``--no-main-job`` skips
them).

Run:  python benchmarks/bench_shell_shape.py [--out FILE.md] [--only NAME ...]
      [--data DIR] [--no-main-job]
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import time
from pathlib import Path

import numpy as np

from handkept import write_keeping_hand_sections
from geotex.mapping import (edge_colors, mapped_tiles, texture_height, textured_solid,
                            tiles_for_quads)
from geotex.mapping.shape import ElementFootprints, element_directions, element_footprints
from geotex.mapping.union import element_contacts
from geotex.mapping.texture import ANCHOR
from geotex.mesh.topology import face_components
from geotex.shells import load_named as load_shell
from geotex.tiles.catalog import load_named as load_tiles
from geotex.tiles.tiling import planar_tiling, random_arrangement

SHELLS = ("spot", "bob", "torus", "blub")
MAIN_JOB = (("spot 15k", "spot_odedstein.obj"), ("kitten 15k", "kitten_gpjs.obj"),
            ("bob 15k", "bob_uv/bob_tri.obj"))
SET = "studs"
RESULTS = Path(__file__).parent / "results"


def planar_figures(tiles) -> dict:
    V, F = planar_tiling(tiles, random_arrangement(tiles, 6, 6, seed=0))
    n, label = face_components(F, V.shape[0])
    fp = element_footprints(V, F, label, np.tile([0.0, 0.0, 1.0], (n, 1)))
    return _figures(fp) | {"elements": n}


def _figures(fp) -> dict:
    return {"cv": round(fp.cv, 4), "aspect_mean": round(float(fp.aspect.mean()), 4),
            "aspect_p95": round(float(np.percentile(fp.aspect, 95)), 4),
            "aspect_max": round(float(fp.aspect.max()), 3)}


def object_footprints(shell, tiles, *, shaped: bool) -> dict:
    """Footprint figures of the elements mapped into ``shell`` (before the union)."""
    pc = shell.polycube
    h = texture_height(shell, tiles)
    colors = edge_colors(pc.layout.edge_axis, tiles.n_colors, seed=0)
    tq = tiles_for_quads(tiles, pc.layout.quad_axes, pc.layout.quad_edge, colors,
                         bare=pc.quad_folded)
    cpu = []
    for _ in range(3):          # CPU seconds: less sensitive to the shared machine's load
        t = time.process_time()
        m = mapped_tiles(shell, tiles, tq, scale=h / tiles.height,
                         anchor=ANCHOR * shell.tile_size, shaped=shaped)
        cpu.append(time.process_time() - t)
    n, label = face_components(m.faces, m.vertices.shape[0])
    normal = element_directions(shell, m, label)
    out = _figures(element_footprints(m.vertices, m.faces, label, normal))
    out["cpu_map"] = round(min(cpu), 3)
    touching = element_contacts(m.vertices, m.faces).touching
    out["meeting"] = int(np.unique(touching).size)
    return out


def printed_footprints(shell, res) -> dict:
    """Footprint figures of the elements as the job ends them (re-seated; left out excluded)."""
    m = res.elements
    label = m.element[m.faces[:, 0]]
    fp = element_footprints(m.vertices, m.faces, label, element_directions(shell, m, label))
    kept = ~res.left_out
    out = _figures(ElementFootprints(fp.area[kept], fp.aspect[kept]))
    return {"printed_" + k: v for k, v in out.items()} | {"left_out": int(res.left_out.sum())}


def main_job_shell(src: Path, work: Path):
    """The shell ``geotex texture SRC_15k.obj --size-mm 80`` builds (as bench_main_job.py)."""
    from bench_main_job import decimated_base
    from geotex.cli.shell import shell_of_file

    base = decimated_base(src, 15000, work / f"{src.stem}_15k.obj")
    return shell_of_file(str(base), None, name=base.stem, size_mm=80.0)


def run_shell(name: str, tiles, *, shaped: bool, shell=None) -> dict:
    shell = load_shell(name) if shell is None else shell
    row = {"shell": name, "map": "shaped" if shaped else "plain", "quads": shell.n_quads,
           "tile_size": shell.tile_size}
    row.update(object_footprints(shell, tiles, shaped=shaped))
    t = time.perf_counter()
    res = textured_solid(shell, tiles, seed=0, shaped=shaped, keep_elements=True)
    s = res.stats
    row.update(printed_footprints(shell, res))
    row.update(seconds_job=round(time.perf_counter() - t, 2), seconds_map=s.seconds["map"],
               elements=s.elements, bare_quads=s.bare_quads,
               open_faces_dropped=s.open_faces_dropped, folded=s.elements_folded,
               floating=s.elements_floating, reseated=s.elements_reseated,
               left_out_at_defects=s.elements_left_out_at_defects,
               printable=bool(res.report.printable))
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=RESULTS / "shell_shape.md")
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--data", type=Path,
                    default=Path(__file__).resolve().parents[2] / "shared" / "data")
    ap.add_argument("--no-main-job", action="store_true")
    args = ap.parse_args()
    tiles = load_tiles(SET)
    planar = planar_figures(tiles)
    print("planar", planar, flush=True)
    rows = []
    for name in SHELLS:
        if args.only and name not in args.only:
            continue
        for shaped in (False, True):
            row = run_shell(name, tiles, shaped=shaped)
            row["cv_ratio"] = round(row["cv"] / planar["cv"], 2)
            row["printed_cv_ratio"] = round(row["printed_cv"] / planar["cv"], 2)
            print(row, flush=True)
            rows.append(row)
    if not args.no_main_job:
        import tempfile

        with tempfile.TemporaryDirectory() as tmp:
            for name, rel in MAIN_JOB:
                if args.only and name.split()[0] not in args.only and name not in args.only:
                    continue
                shell = main_job_shell(args.data / "base" / rel, Path(tmp))
                row = run_shell(name, tiles, shaped=True, shell=shell)
                row["cv_ratio"] = round(row["cv"] / planar["cv"], 2)
                row["printed_cv_ratio"] = round(row["printed_cv"] / planar["cv"], 2)
                print(row, flush=True)
                rows.append(row)
    lines = [
        "# Element shape on objects (issue 14, item 5)", "",
        f"Run {datetime.date.today()} on {platform.machine()}, 2 cores shared with other jobs, "
        f"Python {platform.python_version()}, numpy {np.__version__}, 1-minute load "
        f"{os.getloadavg()[0]:.1f} at the end; `python benchmarks/bench_shell_shape.py`.", "",
        f"Tile set `{SET}`, seed 0. *CV*: coefficient of variation of the element footprint "
        "areas (footprint: the element projected onto its tangent plane) as `mapped_tiles` "
        "lays them, before the job re-seats folded ones; *x planar*: CV over "
        "the CV of the planar 6 x 6 tiling (target <= 1.5); *CV printed*: the same on the "
        "elements as `textured_solid` ends them (re-seated, rooted; the *left out* ones "
        "excluded: still folded, floating with no seat, at defects); "
        "*elongation*: sqrt of the ratio of the footprint's second moments (1 = round), "
        "mean / p95 / max; *bare*: quads without a tile; *open*: faces of open elements "
        "dropped; *folded / floating / at defects*: elements left out; *reseated*: folded "
        "elements shrunk in place that then fit; "
        "*meeting*: mapped elements that touch or cross another one (before the union, "
        "which merges them); *map s*: the map stage, wall (CPU seconds of `mapped_tiles`, "
        "best of 3); *job s*: the whole `textured_solid` with its check. "
        "*plain*: every tile point through the quad map (main before this change); "
        "*shaped*: every small element mapped as one similar shape of one size "
        "(`geotex.mapping.shape`). *X 15k*: the main job's shells (`geotex texture "
        "X_15k.obj --tiles studs --size-mm 80` on `bench_main_job.py`'s decimations), "
        "shaped only.", "",
        f"Planar 6 x 6 tiling: {planar['elements']} elements, CV {planar['cv']}, elongation "
        f"{planar['aspect_mean']} / {planar['aspect_p95']} / {planar['aspect_max']}.", "",
        "| shell | map | elements | CV | x planar | CV printed | x planar printed | left out | "
        "elongation | meeting | bare | open | folded | "
        "floating | at defects | reseated | printable | map s | job s |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['shell']} | {r['map']} | {r['elements']} | {r['cv']} | {r['cv_ratio']} | "
            f"{r['printed_cv']} | {r['printed_cv_ratio']} | {r['left_out']} | "
            f"{r['aspect_mean']} / {r['aspect_p95']} / {r['aspect_max']} | {r['meeting']} | "
            f"{r['bare_quads']} | "
            f"{r['open_faces_dropped']} | {r['folded']} | {r['floating']} | "
            f"{r['left_out_at_defects']} | {r['reseated']} | {r['printable']} | "
            f"{r['seconds_map']} ({r['cpu_map']}) | {r['seconds_job']} |")
    write_keeping_hand_sections(args.out, "\n".join(lines) + "\n")
    args.out.with_suffix(".json").write_text(json.dumps({"planar": planar, "rows": rows},
                                                        indent=1) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
