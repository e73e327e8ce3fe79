"""Benchmark: height-and-tilt extract + reconstruct on a 1M-vertex mesh.

A torus with 1,000,000 vertices carries leaning bumps (a displacement with a
tangential part). geotex extracts the texture over the given base (pseudo-
height, tilt 1-form with the exact per-vertex residual) and reconstructs the
detailed mesh, once with the default tilt encoding (the paper's bounded least
squares, matrix-free, ``encode="lsq"``) and once with the per-edge integral
(``encode="edge"``). For both, the
reconstruction error of the tilt 1-form alone (before the residual) is
reported too. The peer, timed in the same run, is the plain height-field
equivalent with libigl: per-vertex normals of the base, heights as the dot
product of the displacement with them, and displacement along the normals
(which cannot represent the lean: its error is reported too).

The stored 1-form alone is also measured on the issue-22 test shape,
``spiky_sphere(subdivisions=3, spikes=12)`` (seeds 0-2).

Run:  python benchmarks/bench_heighttilt.py [--vertices N] [--repeat R]
           [--reference DIR [--reference-label TEXT] [--rounds K]]
Writes benchmarks/results/heighttilt_speed.md and .json.  With ``--reference``
(a directory holding another geotex source tree, e.g. ``git archive`` of an
older commit) the default extract + reconstruct is also timed in child
processes that alternate between that tree and this one, K rounds of R
repeats each, so that both see the same machine load; user and system CPU
seconds are reported beside wall seconds.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

import igl
import numpy as np

from geotex.heighttilt import apply_texture, decode_tilt, extract_texture, spiky_sphere
from geotex.heighttilt.base import base_normals
from geotex.heighttilt.extract import displacement_to_height_tilt
from geotex.jit import JIT_MIN_SIZE
from geotex.mesh import topology
from geotex.heighttilt import _kernels as kernels
from geotex.mesh.primitives import torus

RESULTS = Path(__file__).parent / "results" / "heighttilt_speed.md"
ROOT = Path(__file__).resolve().parent.parent


def textured_torus(n_vertices: int):
    n_minor = int(round(np.sqrt(n_vertices / 3)))
    n_major = n_vertices // n_minor
    Vs, F = torus(1.0, 0.35, n_major=n_major, n_minor=n_minor)
    N = np.asarray(igl.per_vertex_normals(Vs, F), dtype=np.float64)
    u = np.arctan2(Vs[:, 1], Vs[:, 0])
    v = np.arctan2(Vs[:, 2], np.hypot(Vs[:, 0], Vs[:, 1]) - 1.0)
    bump = 0.03 * np.maximum(0.0, np.sin(24 * u) * np.sin(8 * v)) ** 2
    lean = np.stack([-np.sin(u), np.cos(u), np.zeros_like(u)], 1)   # along the ring
    lean -= N * np.einsum("ij,ij->i", lean, N)[:, None]
    return Vs + bump[:, None] * (N + 0.8 * lean), F, Vs


def best(fn, repeat):
    """Best wall seconds of ``repeat`` calls, best CPU seconds, and the last result.

    CPU seconds are ``time.process_time`` (user + system of this process): the
    machine is shared, so wall time includes waiting for a core.
    """
    t_best, c_best, out = float("inf"), float("inf"), None
    for _ in range(repeat):
        t, c = time.perf_counter(), time.process_time()
        out = fn()
        c_best = min(c_best, time.process_time() - c)
        t_best = min(t_best, time.perf_counter() - t)
    return t_best, c_best, out


def form_error(Vs, F, tex, t_true):
    """Relative RMS and max error of the tilt decoded from the 1-form alone."""
    miss = decode_tilt(Vs, F, tex.tilt) - t_true
    rel = float(np.linalg.norm(miss) / np.linalg.norm(t_true))
    return rel, float(np.linalg.norm(miss, axis=1).max())


def first_touch_cost():
    """Seconds to fill a fresh 24 MB array, and to fill it again (page-fault cost)."""
    t = time.perf_counter()
    a = np.empty(3_000_000)
    a[:] = 1.0
    t1 = time.perf_counter()
    a[:] = 2.0
    t2 = time.perf_counter()
    return t1 - t, t2 - t1


def spiky_form_errors():
    """Relative L2 error of the 1-form alone on spiky_sphere(3, 12), seeds 0-2."""
    out = {}
    for encode in ("lsq", "edge"):
        errs = []
        for seed in range(3):
            V0, F, Vs = spiky_sphere(subdivisions=3, spikes=12, seed=seed)
            nrm = base_normals(Vs, F)
            _, t = displacement_to_height_tilt(V0 - Vs, nrm)
            t -= np.einsum("ij,ij->i", t, nrm)[:, None] * nrm
            tex, _ = extract_texture(V0, F, base=Vs, encode=encode)
            errs.append(form_error(Vs, F, tex, t)[0])
        out[encode] = errs
    return out


def child_timing(vertices: int, repeat: int) -> None:
    """Print (JSON) wall, user and system seconds of ``repeat`` default round trips."""
    V0, F, Vs = textured_torus(vertices)
    runs = []
    for _ in range(repeat):
        r0, w = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
        tex, _ = extract_texture(V0, F, base=Vs)
        apply_texture(Vs, F, tex)
        r1 = resource.getrusage(resource.RUSAGE_SELF)
        runs.append({"wall": time.perf_counter() - w, "user": r1.ru_utime - r0.ru_utime,
                     "sys": r1.ru_stime - r0.ru_stime})
    print(json.dumps(runs))


#: glibc settings that keep freed memory in the process (no page faults on reuse)
KEEP_MEMORY = {"MALLOC_MMAP_THRESHOLD_": str(2 ** 32), "MALLOC_TRIM_THRESHOLD_": str(2 ** 33)}


def compare(reference: str, vertices: int, repeat: int, rounds: int) -> dict:
    """Alternate child processes on the reference tree and on this one (also with
    glibc keeping freed memory, :data:`KEEP_MEMORY`, to show the page-fault share)."""
    variants = (("reference", reference, {}), ("this tree", str(ROOT), {}),
                ("this tree, freed memory kept", str(ROOT), KEEP_MEMORY))
    out = {label: [] for label, _, _ in variants}
    for _ in range(rounds):
        for label, path, extra in variants:
            env = dict(os.environ, PYTHONPATH=path, **extra)
            done = subprocess.run([sys.executable, __file__, "--child", "--vertices",
                                   str(vertices), "--repeat", str(repeat)],
                                  env=env, capture_output=True, text=True, check=True)
            out[label] += json.loads(done.stdout.strip().splitlines()[-1])
    return out


def comparison_lines(runs: dict, reference_label: str, rounds: int, repeat: int) -> list[str]:
    def med(v):
        return float(np.median(v))
    lines = [f"Same-load comparison (default encoding, extract + reconstruct): child processes "
             f"alternating between the reference ({reference_label}) and this tree, {rounds} "
             f"rounds of {repeat}; seconds. The last row sets "
             + ", ".join(f"`{k}={v}`" for k, v in KEEP_MEMORY.items())
             + " (glibc keeps freed memory, so large temporaries are not page-faulted "
             "again): its system time is what fresh memory costs the others.", "",
             "| tree | best wall | median wall | best user + sys | median user | median sys |",
             "|---|---|---|---|---|---|"]
    for label, rs in runs.items():
        lines.append(f"| {label} | {min(r['wall'] for r in rs):.2f} | "
                     f"{med([r['wall'] for r in rs]):.2f} | "
                     f"{min(r['user'] + r['sys'] for r in rs):.2f} | "
                     f"{med([r['user'] for r in rs]):.2f} | {med([r['sys'] for r in rs]):.2f} |")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vertices", type=int, default=1_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-record", action="store_true")
    ap.add_argument("--reference", help="another geotex source tree to compare with")
    ap.add_argument("--reference-label", default="reference tree")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child_timing(args.vertices, args.repeat)
        return
    load_start = os.getloadavg()
    fresh, again = first_touch_cost()
    V0, F, Vs = textured_torus(args.vertices)
    diag = float(np.linalg.norm(np.ptp(V0, axis=0)))
    _, t_true = displacement_to_height_tilt(V0 - Vs, base_normals(Vs, F))

    rows, record = [], {"vertices": int(V0.shape[0]), "faces": int(F.shape[0]),
                        "repeat": args.repeat, "machine": platform.machine(),
                        "cores": os.cpu_count(), "numpy": np.__version__, "runs": {}}
    runs = [("lsq", "lsq", "geotex height + tilt, least-squares encoding (default)"),
            ("lsq-numpy", "lsq", "the same, numpy only (the path below `JIT_MIN_SIZE`: "
             "no compiled loops)"),
            ("edge", "edge", "geotex height + tilt, per-edge encoding")]
    for key, encode, label in runs:
        limit = 10 ** 12 if key == "lsq-numpy" else JIT_MIN_SIZE
        kernels.JIT_MIN_SIZE = topology.JIT_MIN_SIZE = limit
        t_ext, c_ext, (tex, _) = best(lambda: extract_texture(V0, F, base=Vs, encode=encode),
                                      args.repeat)
        t_app, c_app, V = best(lambda: apply_texture(Vs, F, tex), args.repeat)
        kernels.JIT_MIN_SIZE = topology.JIT_MIN_SIZE = JIT_MIN_SIZE
        err = float(np.abs(V - V0).max()) / diag
        rel, mx = form_error(Vs, F, tex, t_true)
        rows.append(f"| {label} | {t_ext:.2f} / {c_ext:.2f} | {t_app:.2f} / {c_app:.2f} | "
                    f"{t_ext + t_app:.2f} / {c_ext + c_app:.2f} | "
                    f"{err:.1e} | {rel:.3f} / {mx:.3f} |")
        record["runs"][key] = {"extract_s": t_ext, "reconstruct_s": t_app,
                                  "total_s": t_ext + t_app, "extract_cpu_s": c_ext,
                                  "reconstruct_cpu_s": c_app, "total_cpu_s": c_ext + c_app,
                                  "max_error_over_diag": err,
                                  "form_rel_rms": rel, "form_max": mx}
        print(rows[-1], flush=True)
    total = record["runs"]["lsq"]["total_s"]
    total_cpu = record["runs"]["lsq"]["total_cpu_s"]

    def height_field():
        N = np.asarray(igl.per_vertex_normals(Vs, F), dtype=np.float64)
        h = np.einsum("ij,ij->i", V0 - Vs, N)
        return Vs + h[:, None] * N
    t_hf, c_hf, Vh = best(height_field, args.repeat)
    err_hf = float(np.linalg.norm(Vh - V0, axis=1).max()) / diag
    record["height_field_peer_s"] = t_hf
    record["height_field_max_error_over_diag"] = err_hf
    spiky = spiky_form_errors()
    # a fresh process: its first round trip loads numba and the cached compiled
    # loops (compiling them instead on the first run on a machine)
    fresh_runs = json.loads(subprocess.run(
        [sys.executable, __file__, "--child", "--vertices", str(args.vertices), "--repeat", "2"],
        check=True, capture_output=True, text=True).stdout)
    record["fresh_process_round_trips"] = fresh_runs
    compared = None
    if args.reference:
        compared = compare(args.reference, args.vertices, args.repeat, args.rounds)
        record["comparison"] = {"reference": args.reference_label, "rounds": args.rounds,
                                "runs": compared}
    record["spiky_sphere_form_rel_l2"] = spiky
    record["fresh_24MB_fill_s"], record["refill_24MB_s"] = fresh, again
    load_end = os.getloadavg()
    record["load_average_start"], record["load_average_end"] = load_start, load_end
    record["height_field_peer_cpu_s"] = c_hf

    lines = [
        "# Benchmark: height-and-tilt extract + reconstruct",
        "",
        f"Mesh: bumpy torus, {V0.shape[0]:,} vertices, {F.shape[0]:,} faces, bumps leaning along "
        f"the ring (tilt up to {np.linalg.norm(t_true, axis=1).max():.2f}). Given base (no "
        f"smoothing). Best of {args.repeat} (wall and CPU seconds each the best of its own). "
        f"Machine: {platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, numpy {np.__version__}. "
        "Script: `benchmarks/bench_heighttilt.py`.",
        "",
        "| method | extract (s, wall / CPU) | reconstruct (s, wall / CPU) | total (s, wall / CPU) "
        "| max error / bbox diagonal | 1-form alone: relative RMS / max tilt error |",
        "|---|---|---|---|---|---|",
        *rows,
        f"| height field with libigl normals (peer) | - | - | {t_hf:.2f} / {c_hf:.2f} | "
        f"{err_hf:.1e} | - |",
        "",
        f"Load average (1, 5, 15 min) at the start {load_start[0]:.2f}, {load_start[1]:.2f}, "
        f"{load_start[2]:.2f} and at the end {load_end[0]:.2f}, {load_end[1]:.2f}, "
        f"{load_end[2]:.2f} (2 cores; other jobs: {os.environ.get('OTHER_JOBS', 'not stated')}).",
        "",
        f"Target: at most 2 s for extract + reconstruct; the default takes {total:.2f} s wall "
        f"and {total_cpu:.2f} s CPU: the target is {'met' if total_cpu <= 2.0 else 'not met'} "
        f"on CPU time and {'met' if total <= 2.0 else 'not met'} on wall time. The "
        f"height-field peer is {total / t_hf:.1f}x faster but cannot hold the lean. Both "
        "encodings reconstruct exactly (the per-vertex residual holds what the 1-form "
        "misses); the last column is the tilt decoded from the 1-form alone, relative to "
        "the true tilt. Fresh memory is expensive on this machine: filling a newly "
        f"allocated 24 MB array took {1000 * fresh:.0f} ms, filling it again "
        f"{1000 * again:.0f} ms (page faults), which weighs on all rows. From "
        f"{JIT_MIN_SIZE:,} half-edges or edges up, the edge topology, the decoder, its "
        "transpose and the least-squares CG run as compiled loops (numba, `geotex/jit.py`); "
        "the numpy-only row is the same "
        "code with that threshold lifted. In a fresh process the first round trip took "
        f"{fresh_runs[0]['wall']:.2f} s wall and the second {fresh_runs[1]['wall']:.2f} s: "
        "the first loads numba and the cached compiled code (on the first run on a machine "
        "it compiles them instead, about 5 s, once). Earlier records, best of 3 on a quiet "
        "machine: 4.69 s before the numpy rewrite of the topology sort, decoder transpose "
        "and CG loop; 3.74 s after it (2026-12-06, numpy only).",
        "",
        "1-form alone on `spiky_sphere(subdivisions=3, spikes=12)`, seeds 0, 1, 2 "
        "(relative L2 tilt error; issue 22 asks for at most 0.05 by default): "
        + "; ".join(f"{k}: " + ", ".join(f"{v:.3f}" for v in spiky[k]) for k in spiky) + ".",
    ]
    if compared is not None:
        lines += ["", *comparison_lines(compared, args.reference_label, args.rounds,
                                        args.repeat)]
    text = "\n".join(lines) + "\n"
    print(text)
    if not args.no_record:
        RESULTS.parent.mkdir(exist_ok=True)
        RESULTS.write_text(text)
        RESULTS.with_suffix(".json").write_text(json.dumps(record, indent=2) + "\n")


if __name__ == "__main__":
    main()
