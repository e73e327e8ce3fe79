"""The main job with the own local union wired in, against the boolean alone.

For each row (a ~15k-face base at 80 mm with a tile set and tile size, or a
catalog shell), one shell is built, then ``textured_solid(..., union=U)`` runs
with ``U = "boolean"`` (main's path) and ``U = "auto"`` (the dispatch),
interleaved in one process for ``--repeats`` rounds (order alternating): CPU
seconds of the process (``time.process_time``, manifold3d's threads included)
of the whole job and of `united_with_base` (progress callback: from its
first step to the check), and the
wall seconds of the union and validate stages. Each round's STL is written and its
sha256 compared with the first round's; the last one is read back and judged
by ``geotex check``.

Usage: ``python benchmarks/bench_union_dispatch.py [--data ../shared/data] [--rows NAME ...]``
prints one line per row (Markdown table rows).
"""

from __future__ import annotations

import argparse
import hashlib
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

#: name -> (base file under data/base or catalog shell name, tile size or None, tile set)
ROWS = {
    "spot-studs-auto": ("spot_odedstein.obj", None, "studs"),
    "spot-studs-3.7": ("spot_odedstein.obj", 3.7, "studs"),
    "bob-studs-auto": ("bob_uv/bob_tri.obj", None, "studs"),
    "kitten-studs-auto": ("kitten_gpjs.obj", None, "studs"),
    "spot-chainmail-auto": ("spot_odedstein.obj", None, "chainmail"),
    "spot-weave-auto": ("spot_odedstein.obj", None, "weave"),
    "cat-spot-chainmail": ("spot", None, "chainmail"),
    "cat-spot-weave": ("spot", None, "weave"),
    "cat-spot-studs": ("spot", None, "studs"),
}


def _shell(data: Path, src: str, tile_size, work: Path):
    from geotex.io import read_mesh
    from geotex.shells import build_shell

    if "." not in src:
        from geotex.shells.catalog import load_named
        return load_named(src)
    sys.path.insert(0, str(HERE))
    from bench_main_job import decimated_base

    mesh = read_mesh(decimated_base(data / "base" / src, 15000, work / (Path(src).stem + ".obj")))
    V = mesh.vertices * (80.0 / float(np.ptp(mesh.vertices, axis=0).max()))
    return build_shell(V, mesh.faces, tile_size=tile_size)


def measure(shell, tileset, repeats, work, name):
    from geotex.check import check_mesh
    from geotex.io import read_mesh, write_mesh
    from geotex.mapping import textured_solid
    from geotex.mesh.record import Mesh
    from geotex.tiles.catalog import load_named

    tiles = load_named(tileset)
    out = {}
    for r in range(repeats):
        for u in (("boolean", "auto") if r % 2 == 0 else ("auto", "boolean")):
            marks = {}

            def progress(stage, marks=marks):
                marks.setdefault(stage, time.process_time())

            t = time.process_time()
            res = textured_solid(shell, tiles, seed=0, union=u, progress=progress)
            cpu = time.process_time() - t
            # united_with_base: from its first step to the check (a fallback
            # union runs in the validate stage)
            union_cpu = marks["validate"] - marks["union: folded elements"]
            path = work / f"{name}_{u}_{r}.stl"
            write_mesh(path, Mesh(res.vertices, res.faces))
            sha = hashlib.sha256(path.read_bytes()).hexdigest()
            o = out.setdefault(u, {"cpu": [], "union": [], "union_cpu": [], "sha": set(),
                                   "path": path, "stats": res.stats,
                                   "printable": res.report.printable})
            o["cpu"].append(cpu)
            o["union_cpu"].append(union_cpu)
            o["union"].append(res.stats.seconds["union"] + res.stats.seconds.get("validate", 0))
            o["sha"].add(sha)
    rows = []
    for u, o in out.items():
        back = read_mesh(o["path"])
        rep = check_mesh(back.vertices, back.faces)
        s = o["stats"]
        rows.append(f"| {name} | {shell.tile_size:.3g} | {u} | {s.union_method} | "
                    f"{s.union_fallbacks} | {s.union_retries} | "
                    f"{' '.join(f'{c:.2f}' for c in o['cpu'])} | "
                    f"{' '.join(f'{c:.2f}' for c in o['union_cpu'])} | "
                    f"{' '.join(f'{c:.2f}' for c in o['union'])} | {s.faces:,} | "
                    f"{len(o['sha'])} | {'printable' if rep.printable else 'NOT printable'} | "
                    f"{sorted(o['sha'])[0][:12]} |")
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=str(HERE.parent.parent / "shared" / "data"))
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--rows", nargs="*", default=list(ROWS))
    args = ap.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="geotex-bench-dispatch-"))
    # compiled code loaded and caches warm, both paths (a small catalog shell)
    from geotex.mapping import textured_solid
    from geotex.shells.catalog import load_named as load_shell
    from geotex.tiles.catalog import load_named as load_tiles
    for u in ("boolean", "own"):
        textured_solid(load_shell("torus"), load_tiles("studs"), seed=0, union=u)
    print(f"load {os.getloadavg()[0]:.1f}", flush=True)
    print("| row | tile mm | union= | used | fallbacks | retries | job CPU s per round | "
          "united_with_base CPU s | "
          "union+validate wall s | faces | distinct sha256 | STL check | sha256 |", flush=True)
    for name in args.rows:
        src, ts, tileset = ROWS[name]
        shell = _shell(Path(args.data), src, ts, work)
        for line in measure(shell, tileset, args.repeats, work, name):
            print(line, flush=True)
    print(f"load {os.getloadavg()[0]:.1f} work {work}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
