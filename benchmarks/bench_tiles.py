"""Benchmark: building geometric Wang tile sets with quilted interiors, beside two peers.

For three procedural exemplars (studs, knurl kept on its lattice, scales), in
one run:

1. a 16-tile planar set (2 colours per axis) and a 16-tile isotropic set
   (2 colours shared by all axes), interiors by constrained mesh quilting
   (the default): total time, time per tile, seam check, coverage, tiles
   that fell back to paste;
2. peer A, the same sets with the paste interior (whole exemplar elements
   between the frame's, no synthesis);
3. peer B, the same quilting engine on one tile-sized patch without any
   constraint (``quilt_texture`` on a 1 x 1 domain from a 2 x 2 exemplar
   window, no frame), 16 times with different seeds: what a tile would cost
   if its sides did not matter.

Target (issue 6): a 16-tile planar set in under 60 s; the paper needed
minutes per tile.

Run:  python benchmarks/bench_tiles.py
"""

from __future__ import annotations

import os
import platform
import time
from pathlib import Path

import numpy as np

from geotex.exemplars import exemplar
from geotex.quilting import quilt_texture
from geotex.tiles import build_tileset, check_seams
from geotex.tiles.build import QUILT_WINDOW, _exemplar_arrays

RESULTS = Path(__file__).parent / "results" / "tiles.md"

CASES = (
    ("studs", dict(pitch=0.25, radius=0.09), False),
    ("knurl", dict(pitch=0.25, height=0.1), True),
    ("scales", dict(pitch=0.25, length=0.3, row_spacing=0.17, resolution=12), False),
)


def timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def unconstrained(ex, n=16):
    """Peer B: quilt n tile-sized patches without a frame, from a 2 x 2 window."""
    src = _exemplar_arrays(ex)[0]
    V, F = src.window((0.0, 0.0), (QUILT_WINDOW, QUILT_WINDOW))
    pitch = float(ex.params["pitch"])
    reports = []
    t0 = time.perf_counter()
    for seed in range(n):
        r = quilt_texture(V, F, size=(QUILT_WINDOW, QUILT_WINDOW), out_size=(1.0, 1.0),
                          cell=pitch, seed=seed)
        reports.append(r.report)
    return time.perf_counter() - t0, reports


def main():
    lines = ["# Benchmark: geometric Wang tile sets", ""]
    lines.append(f"Machine: {platform.machine()}, {os.cpu_count()} cores (shared with other "
                 f"jobs), Python {platform.python_version()}, numpy {np.__version__}. "
                 "Script: `benchmarks/bench_tiles.py`. Exemplars 4 x 4 tiles, seed 0.")
    lines += ["", "## Building 16-tile sets", "",
              "| exemplar | set | interior | time (s) | per tile (s) | seams | coverage | "
              "paste fallbacks | vertices |", "|---|---|---|---|---|---|---|---|---|"]
    worst_planar = 0.0
    peers = []
    for kind, params, lattice in CASES:
        ex = exemplar(kind, **params)
        label = f"{kind}{' (lattice)' if lattice else ''}"
        for what, kw in (("planar 2x2 colours", dict(planar=True)),
                         ("isotropic 2 colours", dict(isotropic=True))):
            for interior in ("quilt", "paste"):
                t, ts = timed(lambda: build_tileset(ex, colors=2, lattice=lattice, seed=0,
                                                    interior=interior, **kw))
                rep = check_seams(ts)
                if interior == "quilt" and "planar" in what:
                    worst_planar = max(worst_planar, t)
                fb = ts.metadata.get("paste_fallbacks", "-")
                lines.append(f"| {label} | {what} | {interior} | {t:.2f} | {t / len(ts):.3f} | "
                             f"{'ok' if rep.ok else 'BROKEN'} ({rep.pairs_checked} pairs) | "
                             f"{ts.metadata['coverage_mean']:.0%} | {fb} | "
                             f"{len(ts.vertices)} |")
                print(lines[-1], flush=True)
        tb, reports = unconstrained(ex)
        peers.append(f"| {kind} | 16 | {tb:.2f} | {tb / 16:.3f} | "
                     f"{'yes' if all(r.valid for r in reports) else 'NO'} | "
                     f"{np.mean([r.coverage for r in reports]):.0%} |")
        print(peers[-1], flush=True)
    lines += ["", f"Target: a 16-tile planar set in under 60 s; the slowest quilted one took "
              f"{worst_planar:.1f} s. `seams` is `check_seams` (every ordered pair of tile "
              "sides that may meet; for an isotropic set across all classes). Coverage is "
              "the mean fraction of a tile under an element. A tile falls back to paste "
              "when three quilting attempts are not accepted (side boundaries must stay "
              "bit-identical to the frame's, every element valid).", ""]
    lines += ["## Peer: the same quilting engine on a tile-sized patch, unconstrained", "",
              "| exemplar | patches | time (s) | per patch (s) | valid | coverage |",
              "|---|---|---|---|---|---|", *peers, "",
              "The constrained tile costs more than a free patch of the same size: the "
              "frame's open halves are capped, merged copies are checked against it, and "
              "rejected attempts are quilted again. Paste (whole exemplar elements dropped "
              "into free space around the frame) is an order of magnitude faster; it "
              "covers as much for small separate elements (studs) but much less for dense "
              "textures (knurl, scales), where quilting fits copies against the frame.", "",
              "Load average (1, 5, 15 min) at the end of the run: "
              + ", ".join(f"{x:.2f}" for x in os.getloadavg())
              + " on 2 cores, so other jobs shared the machine during the timings.", ""]
    RESULTS.write_text("\n".join(lines))
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
