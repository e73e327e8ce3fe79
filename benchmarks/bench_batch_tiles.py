"""Benchmark: one catalog tile set built sequentially and on 2 local Dask workers.

The set is rebuilt from its recipe (:func:`geotex.tiles.catalog.rebuild`) once
in this process (``--workers 0``) and once with ``map_tiles`` on a local
cluster of 2 processes (:func:`geotex.batch.run.map_tasks`, what
``geotex tiles build --workers 2`` does; the wall time includes starting the
cluster). Both results are compared array by array with each other and with the
shipped file. The machine is shared with other jobs, so the 1-minute load
average is recorded before and after each run.

Run:  python benchmarks/bench_batch_tiles.py [NAME]   (default: chainmail)
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

from geotex.batch.run import map_tasks
from geotex.tiles.build import built_tile
from geotex.tiles.catalog import load_named, rebuild

RESULTS = Path(__file__).parent / "results"


def same(a, b) -> bool:
    """Whether two tile sets hold the same arrays and metadata."""
    return len(a) == len(b) and a.metadata == b.metadata and all(
        np.array_equal(x, y) for i in range(len(a)) for x, y in zip(a.tile(i), b.tile(i)))


def built_tile_timed(plan, t):
    """:func:`built_tile` and the CPU seconds it took (runs on a worker)."""
    cpu = time.process_time()
    result = built_tile(plan, t)
    return result, time.process_time() - cpu


def on_dask(workers, figures):
    """``map_tiles`` on a local cluster that records worker CPU and the first result's time."""
    def map_tiles(function, plan, n):
        assert function is built_tile
        start = time.perf_counter()
        figures["worker_cpu_seconds"] = 0.0
        for t, (result, cpu) in map_tasks(built_tile_timed, plan, n, workers=workers):
            figures.setdefault("first_tile_seconds", round(time.perf_counter() - start, 2))
            figures["worker_cpu_seconds"] += cpu
            yield t, result
    return map_tiles


def timed(name, map_tiles):
    load = os.getloadavg()[0]
    t, cpu = time.perf_counter(), time.process_time()
    ts = rebuild(name, map_tiles=map_tiles)
    return ts, {"seconds": round(time.perf_counter() - t, 2),
                "client_cpu_seconds": round(time.process_time() - cpu, 2),
                "load_before": round(load, 2), "load_after": round(os.getloadavg()[0], 2)}


def main() -> None:
    name = sys.argv[1] if len(sys.argv) > 1 else "chainmail"
    seq, rs = timed(name, None)
    print("sequential", rs, flush=True)
    figures = {}
    par, rp = timed(name, on_dask(2, figures))
    rp["worker_cpu_seconds"] = round(figures["worker_cpu_seconds"], 2)
    rp["first_tile_seconds"] = figures["first_tile_seconds"]
    print("2 workers", rp, flush=True)
    identical = same(seq, par)
    shipped = same(seq, load_named(name))
    row = {"set": name, "tiles": len(seq), "sequential": rs, "workers_2": rp,
           "speedup": round(rs["seconds"] / rp["seconds"], 2),
           "identical": identical, "identical_to_shipped": shipped,
           "cores": os.cpu_count()}
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "batch_tiles.json").write_text(json.dumps(row, indent=1) + "\n")
    lines = [
        "# Benchmark: one tile set built sequentially vs on 2 Dask workers",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores shared with other jobs, "
        f"Python {platform.python_version()}, numpy {np.__version__}. Script: "
        "`benchmarks/bench_batch_tiles.py`.",
        "",
        f"Catalog set `{name}` ({len(seq)} tiles) rebuilt from its recipe: in this process, "
        "then with `map_tiles` on a local cluster of 2 single-threaded processes "
        "(`geotex tiles build --workers 2`; wall time includes starting the cluster and "
        "scattering the plan). Load = 1-minute load average before / after.",
        "",
        "| run | wall s | client CPU s | worker CPU s (sum) | first tile back after s | "
        "load before / after |",
        "|---|---|---|---|---|---|",
        f"| sequential | {rs['seconds']:.1f} | {rs['client_cpu_seconds']:.1f} | - | - | "
        f"{rs['load_before']:.1f} / {rs['load_after']:.1f} |",
        f"| 2 workers | {rp['seconds']:.1f} | {rp['client_cpu_seconds']:.1f} | "
        f"{rp['worker_cpu_seconds']:.1f} | {rp['first_tile_seconds']:.1f} | "
        f"{rp['load_before']:.1f} / {rp['load_after']:.1f} |",
        "",
        f"Speed-up {row['speedup']:.2f}x measured at that load (the 2 cores are shared "
        "with other jobs, so 2 workers get far less than 2 cores). Byte-identical sets "
        "(every tile array and the "
        f"metadata): {'yes' if identical else 'NO'}; same as the shipped file: "
        f"{'yes' if shipped else 'NO'}.",
        "",
    ]
    (RESULTS / "batch_tiles.md").write_text("\n".join(lines))


if __name__ == "__main__":
    main()
