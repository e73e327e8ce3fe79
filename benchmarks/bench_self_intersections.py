"""Benchmark geotex's self-intersection detector against pymeshlab.

Runs :func:`geotex.check.intersections.self_intersecting_pairs` and
pymeshlab's ``compute_selection_by_self_intersections_per_face`` on the same
meshes in the same process, prints a table and writes it to
``benchmarks/results/self_intersections.md``.

Meshes (about 10k, 100k and 1M faces each):

* ``torus``: a closed torus grid with near-equilateral triangles;
* ``sphere``: a subdivided icosahedron (20k, 330k, 1.3M faces);
* ``cube``: a closed cube made of flat triangulated grids (CAD-like: large
  coplanar regions, right-angle edges);
* ``2 spheres``: two interpenetrating subdivided spheres (with intersections).

The geotex time includes everything from the ``(V, F)`` arrays; the pymeshlab
time is the filter alone (the mesh is already in the ``MeshSet``).  "faces"
columns count the faces each tool flags (faces in at least one reported pair
for geotex), a cross-check of the answers.

Usage::

    python benchmarks/bench_self_intersections.py [--repeats 3] [--quick]
"""

from __future__ import annotations

import argparse
import importlib.metadata
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from geotex.mesh import primitives

from geotex.check.intersections import self_intersecting_pairs

RESULTS = Path(__file__).resolve().parent / "results" / "self_intersections.md"


def icosphere(level, radius=1.0, center=(0.0, 0.0, 0.0)):
    return primitives.icosphere(level, radius=radius, center=center)


def torus(faces, R=1.0, r=0.35):
    nv = max(3, round((faces / 2 * r / R) ** 0.5))
    nu = max(3, round(faces / 2 / nv))
    return primitives.torus(R, r, n_major=nu, n_minor=nv)


def cube(faces):
    n = max(2, round((faces / 12) ** 0.5)) + 1          # grid points per side
    x = np.linspace(-1.0, 1.0, n)
    X, Y = np.meshgrid(x, x, indexing="ij")
    grid = np.stack([X.ravel(), Y.ravel()], axis=1)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    quads = np.stack([a, a + n, a + n + 1, a + 1], axis=1)
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    Vs, Fs, offset = [], [], 0
    for axis in range(3):
        for sign in (-1.0, 1.0):
            P = np.insert(grid, axis, sign, axis=1)
            # outward orientation: flip where the frame is left-handed
            normal = np.cross(P[tris[0, 1]] - P[tris[0, 0]], P[tris[0, 2]] - P[tris[0, 0]])
            f = tris if normal[axis] * sign > 0 else tris[:, ::-1]
            Vs.append(P)
            Fs.append(f + offset)
            offset += len(P)
    V = np.concatenate(Vs)
    F = np.concatenate(Fs)
    key = np.round((V + 1) * (n - 1) * 2).astype(np.int64)    # weld the seams
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return V[first], inv.ravel()[F]


def two_spheres(level):
    V1, F1 = icosphere(level)
    V2, F2 = icosphere(level, radius=0.8, center=(0.7, 0.31, -0.2))
    return np.concatenate([V1, V2]), np.concatenate([F1, F2 + len(V1)])


def meshes(quick):
    sizes = [10_000, 100_000] if quick else [10_000, 100_000, 1_000_000]
    levels = [5, 7] if quick else [5, 7, 8]
    for s in sizes:
        yield "torus", torus(s)
    for lev in levels:
        yield "sphere", icosphere(lev)
    for s in sizes:
        yield "cube", cube(s)
    yield "2 spheres", two_spheres(6)


def time_geotex(V, F, repeats):
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        pairs = self_intersecting_pairs(V, F)
        times.append(time.perf_counter() - t)
    return times, pairs


def time_pymeshlab(V, F, repeats):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        ms.compute_selection_by_self_intersections_per_face()
        times.append(time.perf_counter() - t)
    selected = ms.current_mesh().face_selection_array()
    return times, int(np.count_nonzero(selected))


def _load():
    try:
        return f"{os.getloadavg()[0]:.2f}"
    except (AttributeError, OSError):
        return "?"


def _version(package):
    try:
        return importlib.metadata.version(package)
    except importlib.metadata.PackageNotFoundError:
        return "?"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3, help="runs per tool and mesh")
    parser.add_argument("--quick", action="store_true", help="skip the 1M-face meshes")
    parser.add_argument("--no-write", action="store_true", help="do not write the results file")
    args = parser.parse_args(argv)
    header = ("| mesh | faces | geotex 1st run (s) | geotex median (s) | pymeshlab median (s) "
              "| speed-up | pairs | faces flagged geotex / pymeshlab |")
    rows = [header, "|" + "---|" * 8]
    load_before = _load()
    print(header)
    for name, (V, F) in meshes(args.quick):
        g_times, pairs = time_geotex(V, F, args.repeats)
        p_times, p_flagged = time_pymeshlab(V, F, args.repeats)
        flagged = np.unique(pairs).size
        g_med = statistics.median(g_times)
        p_med = statistics.median(p_times)
        row = (f"| {name} | {len(F):,} | {g_times[0]:.3f} | {g_med:.3f} | {p_med:.3f} "
               f"| {p_med / g_med:.1f}x | {len(pairs):,} | {flagged:,} / {p_flagged:,} |")
        rows.append(row)
        print(row, flush=True)
    machine = (f"{platform.machine()}, {os.cpu_count()} logical CPUs, Python "
               f"{platform.python_version()}, numpy {np.__version__}, "
               f"pymeshlab {_version('pymeshlab')}")
    text = "\n".join([
        "# Self-intersection detection: geotex vs pymeshlab",
        "",
        "Generated by `python benchmarks/bench_self_intersections.py"
        + (" --quick" if args.quick else "") + f" --repeats {args.repeats}`.",
        "",
        f"Machine: {machine}. Load average (1 min) before / after the run: "
        f"{load_before} / {_load()} (other work on the machine slows both tools).",
        "",
        "geotex: `geotex.check.intersections.self_intersecting_pairs(V, F)`, timed from",
        "the arrays (the first run of the process pays for fresh memory; the median",
        "is over all runs). pymeshlab: `compute_selection_by_self_intersections_per_face`",
        "on a mesh already loaded in the `MeshSet`. Both run in the same process, one",
        "after the other. The last column counts the faces each tool flags.",
        "",
        *rows,
        "",
    ])
    if not args.no_write:
        RESULTS.parent.mkdir(parents=True, exist_ok=True)
        RESULTS.write_text(text)
        print(f"written {RESULTS}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
