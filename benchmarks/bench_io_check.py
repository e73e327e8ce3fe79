"""Benchmark: write, read and check a 1M-triangle binary STL.

geotex is timed beside trimesh and pymeshlab doing the same job in the same
run; the results table goes to ``benchmarks/results/io_check.md``.

The job: a closed torus with exactly 1,000,000 triangles.
* write  - write a binary STL
* read   - read that STL back into shared-vertex arrays (STL stores unwelded
           triangles, so every reader merges identical corners)
* check  - the validity questions of ``geotex check``: watertight/manifold,
           orientation, volume, components, Euler characteristic, and
           self-intersections. trimesh has no self-intersection test, so its
           row answers the rest; pymeshlab's row uses its topological measures
           plus its self-intersection face selection.

Run:  python benchmarks/bench_io_check.py [--triangles N]
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from geotex.check import check_mesh
from geotex.io import read_mesh, write_mesh
from geotex.mesh import Mesh
from geotex.mesh.primitives import torus

RESULTS = Path(__file__).parent / "results" / "io_check.md"


def _version(dist: str) -> str:
    from importlib.metadata import version
    return version(dist)


def timed(fn, repeat=3):
    best, out = float("inf"), None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--triangles", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-record", action="store_true", help="do not write the results file")
    args = ap.parse_args()
    n_minor = 500
    n_major = args.triangles // (2 * n_minor)
    V, F = torus(1.0, 0.3, n_major=n_major, n_minor=n_minor)
    mesh = Mesh(V, F)
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "torus.stl"

        # --- geotex
        t_w, _ = timed(lambda: write_mesh(path, mesh), args.repeat)
        t_r, m = timed(lambda: read_mesh(path), args.repeat)
        t_c, rep = timed(lambda: check_mesh(m.vertices, m.faces), 1)
        assert rep.printable and rep.genus == 1 and m.n_faces == F.shape[0]
        rows["geotex"] = (t_w, t_r, t_c, "all checks incl. self-intersections")

        # --- trimesh
        import trimesh
        tm = trimesh.Trimesh(V, F, process=False)
        p2 = Path(tmp) / "tm.stl"
        t_w, _ = timed(lambda: tm.export(p2), args.repeat)
        t_r, tl = timed(lambda: trimesh.load(path, force="mesh"), args.repeat)

        def tm_check():
            x = trimesh.load(path, force="mesh")  # fresh object: trimesh caches answers
            return (x.is_watertight, x.is_winding_consistent, x.volume, x.euler_number,
                    len(x.split(only_watertight=False)))
        t_c, ans = timed(lambda: tm_check(), 1)
        t_c -= t_r  # exclude the reload inside tm_check
        assert ans[0] and ans[1] and tl.faces.shape[0] == F.shape[0]
        rows["trimesh " + _version("trimesh")] = (t_w, t_r, t_c, "no self-intersection test")

        # --- pymeshlab
        import pymeshlab
        p3 = Path(tmp) / "ml.stl"
        ms = pymeshlab.MeshSet()
        ms.add_mesh(pymeshlab.Mesh(V, F.astype(np.int32)))
        t_w, _ = timed(lambda: ms.save_current_mesh(str(p3), binary=True), args.repeat)

        def ml_read():
            s = pymeshlab.MeshSet()
            s.load_new_mesh(str(path))
            return s
        t_r, s = timed(ml_read, args.repeat)

        def ml_check():
            s.get_topological_measures()
            s.get_geometric_measures()
            s.compute_selection_by_self_intersections_per_face()
            return s.current_mesh().selected_face_number()
        t_c, nsel = timed(ml_check, 1)
        assert nsel == 0
        rows["pymeshlab " + _version("pymeshlab")] = (t_w, t_r, t_c, "incl. self-intersections")

    size_mb = (84 + 50 * F.shape[0]) / 1e6
    lines = [
        "# Benchmark: write, read and check a binary STL",
        "",
        f"Mesh: closed torus, {F.shape[0]:,} triangles, {V.shape[0]:,} vertices, "
        f"binary STL {size_mb:.0f} MB. Best of {args.repeat} for write/read, one run for check.",
        f"Machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
        f"numpy {np.__version__}. Script: `benchmarks/bench_io_check.py`.",
        "",
        "| tool | write (s) | read (s) | check (s) | read + check (s) | check covers |",
        "|---|---|---|---|---|---|",
    ]
    for name, (w, r, c, note) in rows.items():
        lines.append(f"| {name} | {w:.2f} | {r:.2f} | {c:.2f} | {r + c:.2f} | {note} |")
    g = rows["geotex"]
    lines.append("")
    lines.append("Ratios (peer time / geotex time; above 1 means geotex is faster):")
    lines.append("")
    for name, (w, r, c, _) in rows.items():
        if name == "geotex":
            continue
        lines.append(f"* {name}: write {w / g[0]:.2f}x, read {r / g[1]:.2f}x, "
                     f"read + check {(r + c) / (g[1] + g[2]):.2f}x")
    text = "\n".join(lines) + "\n"
    print(text)
    if not args.no_record:
        RESULTS.parent.mkdir(exist_ok=True)
        RESULTS.write_text(text)


if __name__ == "__main__":
    main()
