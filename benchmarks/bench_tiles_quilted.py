"""Benchmark: tile sets from a small exemplar, strips cut from it or from a quilted source.

Issue 14 item 2 (``quilted_source`` of ``build_tileset``, ``geotex/tiles/source.py``):
catalog exemplars cropped to a small square (``Exemplar.cropped``: the
elements lying wholly inside) or made that small (the kind's default parameters: the
two that fail today for want of distinct strips), each built twice in the same run, one right
after the other: *before*, strips and interiors cut from the crop itself
(``quilted_source=False``, what main does), and *after*, from a 4 x 4 tile
texture quilted from it first (``quilted_source=True``; ``"auto"``, the
default, chooses the same where the crop offers too few distinct segments).

Per build: whether it builds (else the error), the strips built and their
mean element count, distinct candidate segments of the strip source along
x / y (``distinct_segments``), seams (``check_seams``), mean tile coverage,
the corner density ratio on a random 6 x 6 tiling (seed 0; issue 14 target
0.85, ``benchmarks/bench_tiles_corners.py``), the welded edges on inner
tile sides of that tiling (relief crossing from tile to tile) and the CPU
seconds of the build (``time.process_time``, one process).

Run:  python benchmarks/bench_tiles_quilted.py   (prints a Markdown table and
writes results/tiles_quilted.json)
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from geotex.errors import InputError
from geotex.exemplars import exemplar
from geotex.tiles import check_seams
from geotex.tiles.build import build_tileset, plan_tileset
from geotex.tiles.catalog import CATALOG
from geotex.tiles.strips import distinct_segments

sys.path.insert(0, str(Path(__file__).parent))
from bench_tiles_corners import measure  # noqa: E402

RESULTS = Path(__file__).parent / "results"

# (catalog recipe, side, "crop" its exemplar or "make" one of its kind that size with the
# kind's default parameters, build options)
CASES = (
    ("studs", 1.3, "crop", dict(colors=2, isotropic=True, seed=4)),
    ("studs", 0.9, "crop", dict(colors=1, isotropic=True, seed=4)),
    ("scales-planar", 1.3, "crop", dict(colors=2, planar=True, seed=2)),
    ("studs", 1.1, "crop", dict(colors=2, planar=True, seed=0)),
    ("studs", 1.1, "make", dict(colors=2, seed=0)),
    ("scales-planar", 1.3, "make", dict(colors=2, planar=True, seed=0)),
)


def small(name: str, side: float, how: str):
    """The recipe's exemplar cropped to ``side`` (or its kind made that size, defaults)."""
    r = CATALOG.recipe(name)
    if how == "make":
        return exemplar(r["exemplar"]["name"], size=(side, side))
    return exemplar(r["exemplar"]["name"], **r["exemplar"].get("params", {})).cropped((side, side))


def run(ex, options: dict, quilted) -> dict:
    t0 = time.process_time()
    try:
        ts = build_tileset(ex, interior="quilt", quilted_source=quilted, **options)
    except InputError as exc:
        return {"builds": False, "error": str(exc), "cpu_s": round(time.process_time() - t0, 2)}
    cpu = time.process_time() - t0
    planned = plan_tileset(ex, interior="quilt", quilted_source=quilted, **options)
    src = planned.plan.src
    strips = [st for cls in sorted(planned.strips) for st in planned.strips[cls]]
    if options.get("isotropic"):
        strips = planned.strips[0]
    seams = check_seams(ts)
    m = measure(ts)
    return {"builds": True, "cpu_s": round(cpu, 2), "tiles": len(ts), "strips": len(strips),
            "elements_per_strip": round(float(np.mean([len(st.boxes) for st in strips])), 2),
            "segments": [distinct_segments(src.lo, src.hi, src.size, along=a) for a in (0, 1)],
            "seamless": bool(seams.ok), "coverage": ts.metadata["coverage_mean"],
            "corner_ratio": m["ratio"], "side_edges": m["sides"]["edges"],
            "source": ts.metadata.get("quilted_source")}


def main() -> None:
    rows = []
    for name, side, how, options in CASES:
        ex = small(name, side, how)
        row = {"recipe": name, "crop": side, "how": how, "elements": ex.n_elements,
               "options": options}
        for label, quilted in (("before", False), ("after", True)):
            row[label] = run(ex, options, quilted)
            print(name, side, how, label, row[label], flush=True)
        rows.append(row)
    load = os.getloadavg()
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "tiles_quilted.json").write_text(json.dumps(
        {"load_end": [round(x, 2) for x in load], "rows": rows}, indent=1) + "\n")

    def cell(r, key, fmt="{}"):
        return fmt.format(r[key]) if r.get("builds") else "-"

    print("\n| exemplar | set | source | builds | strips (elements each) | "
          "distinct segments x / y | seamless | coverage | corner ratio | side edges | CPU s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for row in rows:
        kind = ("isotropic" if row["options"].get("isotropic") else
                "planar" if row["options"].get("planar") else "complete") + \
            f" {row['options']['colors']} col., seed {row['options']['seed']}"
        for label in ("before", "after"):
            r = row[label]
            src = "exemplar itself" if label == "before" else "quilted 4 x 4"
            built = "yes" if r["builds"] else f"no: {r['error'][:60]}"
            what = "cropped to" if row["how"] == "crop" else "made"
            print(f"| {row['recipe']} {what} {row['crop']} x {row['crop']} "
                  f"({row['elements']} el.) | "
                  f"{kind} | {src} | {built} | "
                  f"{cell(r, 'strips')} ({cell(r, 'elements_per_strip')}) | "
                  f"{'/'.join(map(str, r['segments'])) if r['builds'] else '-'} | "
                  f"{cell(r, 'seamless')} | {cell(r, 'coverage', '{:.3f}')} | "
                  f"{cell(r, 'corner_ratio', '{:.2f}')} | {cell(r, 'side_edges')} | "
                  f"{r['cpu_s']} |")
    print(f"\nload average at the end: {load[0]:.2f}, {load[1]:.2f}, {load[2]:.2f}")


if __name__ == "__main__":
    main()
