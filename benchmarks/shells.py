"""Benchmark: shells at the automatic tile size over the base corpus and generated genus shapes.

For every closed printable base of ``/work/shared/data/base`` (skipped when
missing) and every generated shape (``plate_with_holes`` of genus 0, 1, 2, 3,
5, 8, 12, the genus-3 plate of the tests with small holes, tilted, and
``sphere_with_rod``), ``build_shell(V, F)`` with the tile size
chosen automatically: genus, tile size chosen (as a fraction of the largest
extent), attempts of the search, quads, bare quads, coverage (fraction of the
base area within one tile and within a quarter tile of the fitted surface),
distortion, and the build time with its stage breakdown (the search's
attempts are in the voxels / fit stages), with the 1-minute load average at
each row (the machine is shared).

Targets: no bare quads, coverage within one tile >= 0.99, shell build <= 2 s
for a 15k-face base once the size is known (column *at size*: the same build
with the chosen size given explicitly).

Peer: the geometric Wang-tile paper (DESIGN.md section 5.3) reports a few
seconds for 53-322 tiles on 4k-15k-face bases on a 2 GHz dual core; it is
quoted, not run (no code is available).

Run:  python benchmarks/shells.py [--out benchmarks/results/shells.md] [--only NAME ...]
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import time
from pathlib import Path

import numpy as np

from geotex.shells import SHELL_STAGES, build_shell

SHARED = Path("/work/shared/data/base")
CORPUS = (
    ("spot_odedstein", "spot_odedstein.obj"), ("spot_lowres", "spot_lowres_odedstein.obj"),
    ("spot_uv", "spot_uv/spot.obj"), ("bob_tri", "bob_uv/bob_tri.obj"),
    ("bob_small", "bob_small_geometrycentral.ply"), ("blub", "blub_fish_lowres_odedstein.obj"),
    ("fertility", "fertility_libigl.off"), ("kitten", "kitten_gpjs.obj"),
    ("rocker_arm", "rocker_arm_ajacobson.obj"), ("torus", "torus_odedstein.obj"),
    ("double_torus", "double_torus_gpjs.obj"), ("bust", "bust_max_planck_decimated_libigl.obj"),
    ("fandisk", "fandisk_trimesh.obj"), ("sphere", "sphere_odedstein.obj"),
    ("cube", "cube_odedstein.obj"), ("plate_holes", "plate_holes_trimesh.STL"),
)
GENERATED_GENUS = (0, 1, 2, 3, 5, 8, 12)


def _bases(only):
    from geotex.io import read_mesh
    from geotex.mesh.primitives import plate_with_holes, sphere_with_rod

    for name, file in CORPUS:
        if (only and name not in only) or not (SHARED / file).is_file():
            continue
        m = read_mesh(SHARED / file)
        yield name, m.vertices, m.faces
    for g in GENERATED_GENUS:
        if not only or f"plate_g{g}" in only:
            yield (f"plate_g{g}", *plate_with_holes(g))
    if not only or "plate_g3_tilted" in only:
        # small holes off the grid axes: the 1/12 default does not resolve them
        from scipy.spatial.transform import Rotation

        V, F = plate_with_holes(3, hole=0.2, bar=0.6, thickness=0.4, cell=0.06)
        yield ("plate_g3_tilted",
               V @ Rotation.from_euler("zx", [30, 20], degrees=True).as_matrix().T, F)
    if not only or "sphere_rod" in only:
        yield ("sphere_rod", *sphere_with_rod())


def _timed(fn):
    marks = []
    t0 = time.perf_counter()
    out = fn(lambda stage: marks.append((stage, time.perf_counter())))
    t1 = time.perf_counter()
    marks.append(("end", t1))
    per = {}
    for (s, a), (_, b) in zip(marks[:-1], marks[1:]):
        per[s] = per.get(s, 0.0) + (b - a)
    return out, t1 - t0, per


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "shells.md"))
    ap.add_argument("--only", nargs="*", default=None)
    args = ap.parse_args()
    rows = []
    for name, V, F in _bases(set(args.only or ())):
        ext = float(np.ptp(V, axis=0).max())
        try:
            shell, total, per = _timed(lambda p: build_shell(V, F, progress=p))
        except Exception as exc:  # noqa: BLE001 - a failure is a result here
            rows.append(f"| {name} | {F.shape[0]} | | failed: {exc} |" + " |" * 9)
            print(name, "FAILED", exc, flush=True)
            continue
        pc = shell.polycube
        cpu = time.process_time()
        _, again, _ = _timed(lambda p: build_shell(V, F, tile_size=pc.tile_size, progress=p))
        cpu = time.process_time() - cpu
        chi = V.shape[0] - 3 * F.shape[0] // 2 + F.shape[0]
        d, c = pc.diagnostics.distortion, pc.diagnostics.coverage
        attempts = pc.diagnostics.tile_search["attempts"]
        fitted = sum(1 for a in attempts if "quads" in a)
        stages = " / ".join(f"{per.get(s, 0.0):.2f}" for s in SHELL_STAGES)
        rows.append(
            f"| {name} | {F.shape[0]} | {(2 - chi) // 2} | 1/{ext / pc.tile_size:.1f} | "
            f"{len(attempts)} ({fitted} fitted) | {pc.layout.n_quads} | "
            f"{int(pc.quad_folded.sum())} | "
            f"{c['within_tile']:.4f} | {c['within_quarter_tile']:.4f} | "
            f"{d['area_mean']:.3f} / {d['angle_mean']:.3f} | {shell.max_height / pc.tile_size:.2f} | "
            f"**{total:.2f}** | {again:.2f} ({cpu:.2f}) | {stages} | {os.getloadavg()[0]:.1f} |")
        print(rows[-1], flush=True)
    head = (
        f"# Shells at the automatic tile size\n\n"
        f"Run {datetime.date.today()} on {platform.machine()}, {os.cpu_count()} cores shared with "
        f"other jobs, Python {platform.python_version()}, numpy {np.__version__}; "
        f"`python benchmarks/shells.py`.\n\n"
        "`build_shell(V, F)` with `tile_size=None`: the search tries sizes from 1/12 of the "
        "largest extent down in steps of 2^-1/4 and keeps the first whose voxel polycube has "
        "the base's genus, leaves no quad bare and has 99 % of the base area within one tile "
        "of the fitted surface. *tile*: the size chosen, as a fraction of the largest extent; "
        "*attempts*: sizes tried (those that resolved the genus were fitted); *bare*: quads "
        "left without a tile; *1 tile / 1/4 tile*: fraction of the base area within one tile "
        "/ a quarter tile of the fitted surface; *distortion*: area-weighted mean area / angle "
        "error; *h*: safe height in tiles; *s*: seconds for the whole automatic build, *at "
        "size*: the build again with the chosen size given (the cost of one shell), in "
        "brackets its CPU seconds (all threads; less sensitive to the shared machine's "
        "load); stages: "
        + " / ".join(SHELL_STAGES) + " (seconds, the search's attempts included); *load*: "
        "1-minute load average after the row.\n\n"
        "Peer (quoted, not run: no code is available): the geometric Wang-tile paper "
        "(DESIGN.md 5.3) reports a few seconds for 53-322 tiles on 4k-15k-face bases on a "
        "2 GHz dual core.\n\n"
        "| base | faces | genus | tile | attempts | quads | bare | 1 tile | 1/4 tile | "
        "distortion | h | s | at size | stages s | load |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(head + "\n".join(rows) + "\n")
    print("wrote", args.out)


if __name__ == "__main__":
    main()
