"""Benchmark geotex's self-intersection test against libigl and pymeshlab.

Times, on the same ``(V, F)`` arrays in one process:

* geotex: :func:`geotex.check.intersections.self_intersecting_pairs`;
* libigl: ``igl.predicates.find_self_intersections`` (AABB tree, exact
  predicates; reports pairs);
* pymeshlab: ``compute_selection_by_self_intersections_per_face`` (uniform
  grid; selects faces), on a mesh already loaded in the ``MeshSet``.

Meshes: a torus and an icosphere at about 300k and 1M faces, a textured
output (``spot`` shell with ``studs`` tiles, about 390k faces), a closed cube
of finely triangulated flat sides (coplanar neighbours everywhere) at about
300k and 1M faces, and the degenerate case of 1,000 to 16,000 random faces on
the 8 corners of a cube (many duplicates, every face sharing vertices with
every other).  The peers are skipped where they would run for minutes on the
degenerate case (pymeshlab took 43 s at 2,000 faces, libigl grows
quadratically); skipped cells say so.

The 1-minute load average is recorded beside every row: the machine is shared,
and other work slows every tool.

Usage::

    python benchmarks/bench_intersections.py [--repeats 3] [--quick]
        [--textured /tmp/spot_studs.npz]
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

from geotex.check.intersections import self_intersecting_pairs
from geotex.mesh import primitives

RESULTS = Path(__file__).resolve().parent / "results" / "intersections.md"
#: Largest degenerate case each peer is run on (see the module docstring).
PEER_LIMIT = {"igl": 8000, "pymeshlab": 1000}


def torus(faces, R=1.0, r=0.35):
    nv = max(3, round((faces / 2 * r / R) ** 0.5))
    nu = max(3, round(faces / 2 / nv))
    return primitives.torus(R, r, n_major=nu, n_minor=nv)


def cube(faces):
    """Closed cube of six flat triangulated grids, welded, about ``faces`` faces."""
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
            normal = np.cross(P[tris[0, 1]] - P[tris[0, 0]], P[tris[0, 2]] - P[tris[0, 0]])
            f = tris if normal[axis] * sign > 0 else tris[:, ::-1]
            Vs.append(P)
            Fs.append(f + offset)
            offset += len(P)
    V = np.concatenate(Vs)
    F = np.concatenate(Fs)
    key = np.round((V + 1) * (n - 1) * 2).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    return V[first], inv.ravel()[F]


def cube_corner_faces(m, seed=0):
    """``m`` random faces (distinct corners) on the 8 corners of a cube."""
    rng = np.random.default_rng(seed)
    V = np.array([[x, y, z] for x in (0.0, 1.0) for y in (0.0, 1.0) for z in (0.0, 1.0)])
    F = np.argsort(rng.random((m, 8)), axis=1)[:, :3].astype(np.int64)
    return V, F


def textured(path):
    if path and Path(path).exists():
        data = np.load(path)
        return data["V"], data["F"].astype(np.int64)
    from geotex.mapping import textured_solid
    from geotex.shells import load_named
    from geotex.tiles import load_named as load_tiles

    r = textured_solid(load_named("spot"), load_tiles("studs"), seed=1, check=False)
    V, F = np.asarray(r.vertices, float), np.asarray(r.faces, np.int64)
    if path:
        np.savez(path, V=V, F=F)
    return V, F


def meshes(args):
    sizes = [300_000] if args.quick else [300_000, 1_000_000]
    for s in sizes:
        yield "torus", torus(s), False
    for level in ([7] if args.quick else [7, 8]):
        yield "sphere", primitives.icosphere(level), False
    yield "textured (spot + studs)", textured(args.textured), False
    for s in sizes:
        yield "flat-sided cube", cube(s), False
    for m in (1000, 2000, 4000, 8000, 16000):
        yield "8 cube corners", cube_corner_faces(m), True


def _timed(fn, repeats):
    """Median wall-clock and CPU (all threads of the process) seconds, last output."""
    wall, cpu, out = [], [], None
    for _ in range(repeats):
        t, c = time.perf_counter(), time.process_time()
        out = fn()
        wall.append(time.perf_counter() - t)
        cpu.append(time.process_time() - c)
    return (statistics.median(wall), statistics.median(cpu)), out


def _cell(t):
    return f"{t[0]:.3f} ({t[1]:.2f})"


def time_geotex(V, F, repeats):
    t, pairs = _timed(lambda: self_intersecting_pairs(V, F), repeats)
    return t, pairs.shape[0], np.unique(pairs).size


def time_igl(V, F, repeats):
    import igl.predicates

    Fi = np.ascontiguousarray(F, dtype=np.int64)
    Vi = np.ascontiguousarray(V, dtype=np.float64)
    t, out = _timed(lambda: igl.predicates.find_self_intersections(Vi, Fi), repeats)
    return t, out[1].shape[0]


def time_pymeshlab(V, F, repeats):
    import pymeshlab

    ms = pymeshlab.MeshSet()
    ms.add_mesh(pymeshlab.Mesh(vertex_matrix=V, face_matrix=F.astype(np.int32)))
    t, _ = _timed(ms.compute_selection_by_self_intersections_per_face, repeats)
    return t, int(np.count_nonzero(ms.current_mesh().face_selection_array()))


def _load():
    try:
        return f"{os.getloadavg()[0]:.1f}"
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
    parser.add_argument("--textured", default="/tmp/geotex_bench_spot_studs.npz",
                        help="cache .npz of the textured output (made if missing)")
    parser.add_argument("--no-write", action="store_true", help="do not write the results file")
    args = parser.parse_args(argv)
    header = ("| mesh | faces | geotex s (CPU s) | libigl s (CPU s) | pymeshlab s (CPU s) "
              "| load before / after "
              "| pairs geotex / libigl | faces flagged geotex / pymeshlab |")
    rows = [header, "|" + "---|" * 8]
    print(header, flush=True)
    for name, (V, F), degenerate in meshes(args):
        before = _load()
        repeats = 1 if degenerate else args.repeats
        g_t, g_pairs, g_faces = time_geotex(V, F, repeats)
        m = F.shape[0]
        if degenerate and m > PEER_LIMIT["igl"]:
            i_cell, i_pairs = "skipped", "-"
        else:
            i_t, i_pairs = time_igl(V, F, repeats)
            i_cell, i_pairs = _cell(i_t), f"{i_pairs:,}"
        if degenerate and m > PEER_LIMIT["pymeshlab"]:
            p_cell, p_faces = "skipped", "-"
        else:
            p_t, p_faces = time_pymeshlab(V, F, repeats)
            p_cell, p_faces = _cell(p_t), f"{p_faces:,}"
        row = (f"| {name} | {m:,} | {_cell(g_t)} | {i_cell} | {p_cell} | {before} / {_load()} "
               f"| {g_pairs:,} / {i_pairs} | {g_faces:,} / {p_faces} |")
        rows.append(row)
        print(row, flush=True)
    machine = (f"{platform.machine()}, {os.cpu_count()} logical CPUs, Python "
               f"{platform.python_version()}, numpy {np.__version__}, "
               f"libigl {_version('libigl')}, pymeshlab {_version('pymeshlab')}")
    text = "\n".join([
        "# Self-intersections: geotex vs libigl vs pymeshlab",
        "",
        "Generated by `python benchmarks/bench_intersections.py"
        + (" --quick" if args.quick else "") + f" --repeats {args.repeats}`.",
        "",
        f"Machine: {machine}. The machine is shared with other jobs: the 1-minute",
        "load average before / after each row is given (2 cores; a load above 2",
        "means every tool got only part of a core).",
        "",
        "Times are medians of the runs (one run for the 8-corner cases), wall clock,",
        "with the CPU seconds of the process (all threads) in parentheses: on a",
        "loaded machine the CPU time is the fairer comparison of the work done",
        "(geotex runs on up to two threads here, the peers on one).",
        "From arrays in memory. geotex: `self_intersecting_pairs(V, F)`; libigl:",
        "`igl.predicates.find_self_intersections(V, F)`; pymeshlab:",
        "`compute_selection_by_self_intersections_per_face()` on a loaded `MeshSet`.",
        "libigl counts pairs by its own rules (it reports some pairs of faces that",
        "share vertices, and duplicates, differently); pymeshlab flags faces and",
        "misses coplanar overlaps. \"skipped\": the peer would run for minutes",
        f"(pymeshlab beyond {PEER_LIMIT['pymeshlab']:,} faces on 8 corners: 43 s at 2,000;",
        f"libigl beyond {PEER_LIMIT['igl']:,}: it grows quadratically).",
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
