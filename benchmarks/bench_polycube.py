"""Benchmark: polycube parameterization and shell construction, per stage.

Bases: a 15k-face torus (genus 1), the catalog Spot (1.7k faces) and Spot
decimated to ~15k faces (``/work/shared/data/base/spot_odedstein.obj`` with
fast-simplification; skipped when the file is missing).  Every stage of
``geotex.shells.build_shell`` is timed through its progress callback; a
failure is recorded with its message (geotex refuses to return a broken
polycube).  Point location (``locate_on_quads``) is timed on 1M random quad
points beside the peer ``scipy.spatial.cKDTree.query`` of the same points
(nearest polycube vertex only, which is not a point location: the cheapest
common alternative).

Run:  python benchmarks/bench_polycube.py [--out benchmarks/results/polycube.md]
"""

from __future__ import annotations

import argparse
import datetime
import platform
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from geotex.errors import GeotexError
from geotex.mesh.primitives import torus
from geotex.shells import SHELL_STAGES, build_shell, locate_on_quads


def _bases():
    from geotex.data import sample_path
    from geotex.io import read_mesh

    yield "torus 128x60", torus(n_major=128, n_minor=60), 0.1
    m = read_mesh(sample_path("spot"))
    yield "spot (catalog)", (m.vertices, m.faces), 0.08
    src = Path("/work/shared/data/base/spot_odedstein.obj")
    if src.is_file():
        import fast_simplification

        m = read_mesh(src)
        V, F = fast_simplification.simplify(m.vertices, m.faces,
                                            target_reduction=1 - 15000 / m.n_faces)
        yield "spot decimated", (V, F.astype(np.int64)), 0.1


def _timed_build(V, F, ts):
    marks = []

    def progress(stage):
        marks.append((stage, time.perf_counter()))

    t0 = time.perf_counter()
    try:
        shell = build_shell(V, F, tile_size=ts, progress=progress)
        error = None
    except GeotexError as exc:
        shell, error = None, str(exc)
    t1 = time.perf_counter()
    marks.append(("end", t1))
    per = {}
    for (s, a), (_, b) in zip(marks[:-1], marks[1:]):
        per[s] = per.get(s, 0.0) + (b - a)
    return shell, error, t1 - t0, per


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "polycube.md"))
    args = ap.parse_args()
    rows, loc_rows = [], []
    for name, (V, F), ts in _bases():
        shell, error, total, per = _timed_build(V, F, ts)
        stages = " / ".join(f"{per.get(s, 0.0):.2f}" for s in SHELL_STAGES)
        if shell is None:
            rows.append(f"| {name} | {F.shape[0]} | {ts} | failed: {error[:90]}... | {total:.2f} "
                        f"| {stages} |")
            print(name, "FAILED", f"{total:.2f}s", error[:120])
            continue
        d = shell.distortion
        rows.append(f"| {name} | {F.shape[0]} | {ts} | {shell.n_quads} quads, max h "
                    f"{shell.max_height:.3g}, area {d['area_mean']:.3f}/{d['area_p95']:.3f}, "
                    f"angle {d['angle_mean']:.3f}/{d['angle_p95']:.3f} | {total:.2f} | {stages} |")
        print(name, f"{total:.2f}s", per)
        rng = np.random.default_rng(0)
        k = 1_000_000
        q = rng.integers(0, shell.n_quads, k)
        uv = rng.random((k, 2))
        locate_on_quads(shell, q[:1000], uv[:1000])
        t = time.perf_counter()
        locate_on_quads(shell, q, uv)
        t_loc = time.perf_counter() - t
        c = shell.polycube.quad_corners[q].astype(float)
        pts = c[:, 0] + uv[:, :1] * (c[:, 1] - c[:, 0]) + uv[:, 1:] * (c[:, 3] - c[:, 0])
        tree = cKDTree(shell.polycube.P)
        t = time.perf_counter()
        tree.query(pts)
        t_kd = time.perf_counter() - t
        loc_rows.append(f"| {name} | {k / t_loc / 1e6:.2f} M/s | {k / t_kd / 1e6:.2f} M/s |")
    text = [
        "# PolyCube + shell benchmark", "",
        f"Run {datetime.date.today()} on {platform.machine()} ({platform.processor() or 'cpu'}), "
        "2 cores shared with other jobs; `python benchmarks/bench_polycube.py`.", "",
        "Stages (seconds): " + " / ".join(SHELL_STAGES) + ".  Distortion: area-weighted mean / "
        "95th percentile of the scale-free area error `|log(s1 s2 / R)|` and of the "
        "conformal error `(s1/s2 + s2/s1)/2 - 1`.", "",
        "| base | faces | tile | result | total s | stages s |", "|---|---|---|---|---|---|",
        *rows, "",
        "A *failed* row means geotex refused to return a broken polycube for that base "
        "(labelling robustness on fine organic meshes is the known limitation, see "
        "`shells/README.md`); its time is spent in up to 30 relabel/refine rounds.", "",
        "Point location of 1M random quad points (`locate_on_quads`, face + barycentric "
        "coordinates) beside the peer `scipy.spatial.cKDTree.query` on the same points "
        "(nearest polycube vertex only):", "",
        "| base | locate_on_quads | cKDTree.query (peer) |", "|---|---|---|", *loc_rows, "",
    ]
    Path(args.out).write_text("\n".join(text))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
