"""How much of the exact self-intersection test runs on the calling thread.

For each input, one line of JSON: the CPU seconds of the process (all
threads), the wall seconds, the CPU seconds of the calling thread (the part
that runs serially: the compiled pieces, fan halves and pair tasks run on the
pool), the 1-minute load, and the number and sha256 of the pairs (compare
them between trees).  Medians of ``--repeats`` calls after one warm-up call.

Inputs: ``.npz`` files with ``V``, ``F`` (and ``label`` for ``parts``), or
mesh files (``geotex.io.read_mesh``).  Modes: ``plain``
(``self_intersecting_pairs(V, F)``), ``check`` (as ``check_mesh`` calls it:
unpaired-edge vertices given, distinct faces), ``parts`` (``parts=label``, the
union's element contact test).

Usage::

    PYTHONPATH=<tree> python benchmarks/bench_check_serial.py MODE FILE... [--repeats 3]

Run it for main and a branch alternately; on a shared host compare CPU and
calling-thread CPU, not wall (results/intersections.md, h-check).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import statistics
import time
from pathlib import Path

import numpy as np

from geotex.check.intersections import self_intersecting_pairs
from geotex.io import read_mesh
from geotex.mesh.topology import edge_topology, unpaired_edge_vertices


def _load(path: Path):
    if path.suffix == ".npz":
        d = np.load(path)
        return d["V"], d["F"].astype(np.int64), (d["label"] if "label" in d else None)
    mesh = read_mesh(path)
    return mesh.vertices, mesh.faces, None


def _call(mode, V, F, label):
    unpaired = None
    if mode == "check":
        unpaired = unpaired_edge_vertices(edge_topology(F, len(V)), len(V))
    c, w, t = time.process_time(), time.perf_counter(), time.thread_time()
    if mode == "check":
        pairs = self_intersecting_pairs(V, F, unpaired_vertices=unpaired, distinct_faces=True)
    elif mode == "parts":
        pairs = self_intersecting_pairs(V, F, parts=label)
    else:
        pairs = self_intersecting_pairs(V, F)
    return pairs, time.process_time() - c, time.perf_counter() - w, time.thread_time() - t


def main(argv=None) -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("mode", choices=["plain", "check", "parts"])
    ap.add_argument("files", nargs="+", type=Path)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    for path in args.files:
        V, F, label = _load(path)
        _call(args.mode, V, F, label)
        runs = [_call(args.mode, V, F, label) for _ in range(args.repeats)]
        pairs = runs[-1][0]
        med = [statistics.median(r[k] for r in runs) for k in (1, 2, 3)]
        print(json.dumps(dict(
            file=path.name, mode=args.mode, faces=len(F), cpu=round(med[0], 3),
            wall=round(med[1], 3), caller_cpu=round(med[2], 3),
            load=round(os.getloadavg()[0], 2), pairs=int(len(pairs)),
            sha=hashlib.sha256(np.ascontiguousarray(pairs).tobytes()).hexdigest()[:16])),
            flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
