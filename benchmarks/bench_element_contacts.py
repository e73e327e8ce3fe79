"""The union's contact test: the exact test of all mapped elements on the
global grid against the sweep by elements (``parts=``), same process, A/B.

Spot decimated to 15k faces at 80 mm (the main-job bench's base) with studs,
seed 0, at the automatic tile size (~380k output faces) and at 3.7 mm (~1.2M).
Both answers are compared (they must be equal). CPU seconds of this process,
best of ``--repeats`` interleaved runs; the wall time of that run beside.

Usage: ``python benchmarks/bench_element_contacts.py [--data ../shared/data]``
writes ``benchmarks/results/element_contacts.md``.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def _mapped(shell):
    from geotex.mapping import edge_colors, mapped_tiles, texture_height, tiles_for_quads
    from geotex.mapping.texture import ANCHOR
    from geotex.tiles.catalog import load_named

    tiles = load_named("studs")
    lay = shell.polycube.layout
    tq = tiles_for_quads(tiles, lay.quad_axes, lay.quad_edge,
                         edge_colors(lay.edge_axis, tiles.n_colors, seed=0),
                         bare=shell.polycube.quad_folded)
    scale = texture_height(shell, tiles) / tiles.height
    m = mapped_tiles(shell, tiles, tq, scale=scale, anchor=ANCHOR * shell.tile_size)
    return m.vertices, m.faces


def main(argv=None) -> int:
    sys.path.insert(0, str(HERE))
    from bench_union_split import _shell

    from geotex.check.intersections import self_intersecting_pairs
    from geotex.mesh.topology import face_components

    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=str(HERE.parent.parent / "shared" / "data"))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=str(HERE / "results" / "element_contacts.md"))
    args = ap.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="geotex-bench-contacts-"))
    load0 = os.getloadavg()[0]
    rows = []
    for ts in (None, 3.7):
        shell = _shell(Path(args.data), "spot", ts, work)
        X, G = _mapped(shell)
        _, label = face_components(G, X.shape[0])
        runs = {"grid": lambda: self_intersecting_pairs(X, G),
                "parts": lambda: self_intersecting_pairs(X, G, parts=label)}
        for fn in runs.values():                 # warm up (numba's cached code)
            fn()
        best, out = {}, {}
        for _ in range(args.repeats):
            for name, fn in runs.items():
                c, t = time.process_time(), time.perf_counter()
                out[name] = fn()
                dc, dt = time.process_time() - c, time.perf_counter() - t
                if name not in best or dc < best[name][0]:
                    best[name] = (dc, dt)
        same = bool(np.array_equal(out["grid"], out["parts"]))
        rows.append((shell.tile_size, len(G), int(label.max()) + 1, len(out["grid"]), same,
                     best))
        print(rows[-1], flush=True)
    lines = [
        "# The union's contact test: global grid against the sweep by elements",
        "",
        f"Run {time.strftime('%Y-%m-%d %H:%M')} on {platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}; `python benchmarks/bench_element_contacts.py`. "
        f"CPU s of this process, best of {args.repeats} interleaved runs (wall s of that run); "
        f"1-minute load {load0:.1f} at the start (shared machine: only CPU compares). Spot "
        "decimated to 15k faces at 80 mm, studs, seed 0. `grid`: `self_intersecting_pairs` "
        "of all mapped faces as `element_contacts` ran it before; `parts`: the same with "
        "`parts=` the elements (what it runs now).",
        "",
        "| tile mm | mapped faces | elements | intersecting pairs | same answer | grid CPU (wall) "
        "| parts CPU (wall) |",
        "|---|---|---|---|---|---|---|",
    ]
    for tile, m, n_el, n_pairs, same, best in rows:
        lines.append(f"| {tile:.3g} | {m:,} | {n_el:,} | {n_pairs} | {'yes' if same else 'NO'} | "
                     f"{best['grid'][0]:.2f} ({best['grid'][1]:.2f}) | "
                     f"**{best['parts'][0]:.2f}** ({best['parts'][1]:.2f}) |")
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
