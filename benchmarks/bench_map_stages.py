"""CPU seconds of the steps of ``textured_solid`` on saved shells, warm, one process.

Loads each shell (``geotex texture --shell-out`` files) and the ``studs`` set,
runs ``textured_solid`` once to warm (numba caches, imports), then ``--runs``
times, taking ``time.process_time`` (all threads) at every progress callback:

* map: tile geometry into the shell (:func:`geotex.mapping.place.mapped_tiles`);
* seat: the contact test, re-seating of folded elements, floating elements
  and their roots (up to the union proper), and the base's manifold3d solid;
* groups: element pairs, colouring, the small union of elements that meet;
* boolean: the elements operand's build and the boolean with the base
  (manifold3d);
* tidy: needles and the body (the rest of the union);
* validate: float32 rebuild and the full check.

Prints one JSON line per shell: the minimum over the runs per step, the
run totals, and a SHA-256 of the result's arrays. Compare two checkouts by
running this with each on ``PYTHONPATH``, alternated.

Usage: ``python benchmarks/bench_map_stages.py SHELL.npz [SHELL.npz ...] [--runs N]``
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import time
from pathlib import Path

STEPS = (("map", "map", "union"), ("seat", "union", "union: folded elements"),
         ("groups", "union: folded elements", "union: boolean"),
         ("boolean", "union: boolean", "union: slivers"),
         ("tidy", "union: slivers", "validate"), ("validate", "validate", None))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("shells", nargs="+")
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args(argv)
    import geotex
    from geotex.mapping import textured_solid
    from geotex.shells import load_named as load_shell
    from geotex.tiles.catalog import load_named as load_tiles

    tiles = load_tiles("studs")
    for path in args.shells:
        shell = load_shell(path)
        textured_solid(shell, tiles)
        best, totals = {}, []
        for _ in range(args.runs):
            marks = {}

            def progress(step, marks=marks):
                marks.setdefault(step, time.process_time())

            t0 = time.process_time()
            r = textured_solid(shell, tiles, progress=progress)
            end = time.process_time()
            totals.append(round(end - t0, 3))
            for name, a, b in STEPS:
                dt = (end if b is None else marks[b]) - marks[a]
                best[name] = round(min(best.get(name, dt), dt), 3)
        digest = hashlib.sha256(r.vertices.tobytes() + r.faces.tobytes()).hexdigest()[:16]
        print(json.dumps({"shell": Path(path).stem, "geotex": str(Path(geotex.__file__).parent),
                          "cpu": best, "totals": totals, "load": round(os.getloadavg()[0], 2),
                          "faces": int(r.faces.shape[0]), "sha256": digest}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
