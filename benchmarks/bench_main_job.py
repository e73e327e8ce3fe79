"""The main job end to end, as a user runs it: wall time, stages, peak memory.

Runs, each in its own process (``/usr/bin/time -v`` for the peak memory):

* ``geotex texture BASE --tiles studs -o OUT.stl --size-mm 80 [--tile-size MM]``
  (read, shell, map, union, float32 check, verified STL write) on ~15k-face
  bases at two tile sizes (~300k and ~1M output faces);
* ``geotex map --tiles studs --shell NAME -o OUT.stl --size-mm 80`` with the
  catalog shells, and ``geotex map --tiles studs --shell SHELL.npz -o OUT.stl``
  with the shells the default-size ``geotex texture`` runs saved
  (``--shell-out``: ~15k-face bases at print size, ~370k output faces);
* ``geotex demo``.

Peer in the same run: manifold3d's plain batch union of the same base and
mapped elements (no fold test, no check, no write), the floor of the union
stage; the paper (Wang tiles, seed 004) reports a few seconds of mapping
without the union for 53-322 tiles on 4k-15k-face bases (2 GHz dual core).

Usage: ``python benchmarks/bench_main_job.py [--data ../shared/data] [--quick]``
writes ``benchmarks/results/main_job.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from handkept import write_keeping_hand_sections

HERE = Path(__file__).resolve().parent
GEOTEX = [sys.executable, "-m", "geotex"]


def _timed(argv, cwd) -> tuple[float, float, int, str, float, float]:
    """Run ``argv``; return (wall s, peak MB, exit code, stderr tail, CPU s, 1-min load).

    CPU is user + system time of the process and its children (``/usr/bin/time
    -v``); the load is the 1-minute load average just before the run.
    """
    load = os.getloadavg()[0]
    t = time.perf_counter()
    proc = subprocess.run(["/usr/bin/time", "-v", *argv], cwd=cwd, capture_output=True,
                          text=True)
    wall = time.perf_counter() - t
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", proc.stderr)
    peak = int(m.group(1)) / 1024 if m else float("nan")
    cpu = sum(float(x) for x in re.findall(r"(?:User|System) time \(seconds\): ([\d.]+)",
                                            proc.stderr))
    err = [ln for ln in proc.stderr.splitlines() if ln.startswith("geotex:")]
    return wall, peak, proc.returncode, (err[-1] if err else ""), cpu, load


def decimated_base(src: Path, target: int, out: Path) -> Path:
    """A copy of ``src`` decimated to about ``target`` faces (fast-simplification)."""
    import fast_simplification

    from geotex.io import read_mesh, write_mesh
    from geotex.mesh.record import Mesh

    mesh = read_mesh(src)
    ratio = 1.0 - target / mesh.n_faces
    if ratio > 0:
        V, F = fast_simplification.simplify(mesh.vertices.astype(np.float32),
                                            mesh.faces.astype(np.int32), ratio)
        mesh = Mesh(np.asarray(V, np.float64), np.asarray(F, np.int64))
    write_mesh(out, mesh)
    return out


def _union_peer(report_json: Path, base: Path) -> float | None:
    """manifold3d batch union of the job's base and elements, best of 2."""
    import manifold3d

    from geotex.io import read_mesh
    from geotex.mapping import edge_colors, mapped_tiles, texture_height, tiles_for_quads
    from geotex.mapping.union import element_groups
    from geotex.mesh.solid import manifold_of
    from geotex.mesh.topology import compacted
    from geotex.shells import build_shell
    from geotex.tiles.catalog import load_named

    doc = json.loads(report_json.read_text())
    mesh = read_mesh(base)
    V = mesh.vertices * (80.0 / float(np.ptp(mesh.vertices, axis=0).max()))
    shell = build_shell(V, mesh.faces, tile_size=doc["tile_size"])
    tiles = load_named("studs")
    pc = shell.polycube
    lay = pc.layout
    tq = tiles_for_quads(tiles, lay.quad_axes, lay.quad_edge,
                         edge_colors(lay.edge_axis, tiles.n_colors, seed=0), bare=pc.quad_folded)
    h = texture_height(shell, tiles)
    m = mapped_tiles(shell, tiles, tq, scale=h / tiles.height, anchor=0.2 * shell.tile_size)
    label, group = element_groups(m.vertices, m.faces)
    best = None
    for _ in range(2):
        t = time.perf_counter()
        solids = [manifold_of(shell.base_vertices, shell.base_faces)]
        for g in range(int(group.max()) + 1):
            solids.append(manifold_of(*compacted(m.vertices, m.faces[group[label] == g])))
        manifold3d.Manifold.batch_boolean(solids, manifold3d.OpType.Add).to_mesh64()
        dt = time.perf_counter() - t
        best = dt if best is None else min(best, dt)
    return best


def main(argv=None) -> int:
    start_load = os.getloadavg()[0]
    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=str(HERE.parent.parent / "shared" / "data"))
    ap.add_argument("--quick", action="store_true", help="one base, one size")
    ap.add_argument("--out", default=str(HERE / "results" / "main_job.md"))
    args = ap.parse_args(argv)
    data = Path(args.data)
    work = Path(tempfile.mkdtemp(prefix="geotex-bench-main-"))
    bases = [("spot decimated", data / "base" / "spot_odedstein.obj"),
             ("kitten decimated", data / "base" / "kitten_gpjs.obj"),
             ("bob", data / "base" / "bob_uv" / "bob_tri.obj")]
    if args.quick:
        bases = bases[:1]
    rows_texture, rows_map = [], []
    for label, src in bases:
        base = decimated_base(src, 15000, work / f"{src.stem}_15k.obj")
        for tile in ([None] if args.quick else [None, "small"]):
            out = work / f"{src.stem}_{tile}.stl"
            rep = work / f"{src.stem}_{tile}.json"
            extra = []
            if tile == "small":
                # about 3.3x the quads of the automatic size: ~1M output faces
                prev = json.loads((work / f"{src.stem}_None.json").read_text())
                extra = ["--tile-size", f"{prev['tile_size'] / 1.8:.4g}"]
            if tile is None:              # the shell, for the ~370k-face 'geotex map' rows
                extra = ["--shell-out", str(work / f"{src.stem}_shell.npz")]
            wall, peak, code, err, cpu, load = _timed(
                GEOTEX + ["texture", str(base), "--tiles", "studs", "-o", str(out),
                          "--size-mm", "80", "--report", str(rep)] + extra, work)
            row = {"base": label, "faces_in": 15000, "wall": wall, "peak": peak,
                   "code": code, "err": err, "cpu": cpu, "load": load}
            if code == 0:
                doc = json.loads(rep.read_text())
                row.update(tile=doc["tile_size"], quads=doc["stats"]["quads"],
                           faces=doc["stats"]["faces"], seconds=doc["seconds"],
                           retries=doc["stats"]["union_retries"])
                row["peer_union"] = _union_peer(rep, base)
                verdict = subprocess.run(GEOTEX + ["check", str(out)], capture_output=True)
                row["check"] = "yes" if verdict.returncode == 0 else "NO"
            rows_texture.append(row)
            print(row, flush=True)
    shells = [(s, s, ["--size-mm", "80"]) for s in
              (["spot"] if args.quick else ["spot", "bob", "torus"])]
    shells += [(f"{label} 15k (saved by texture)", str(work / f"{src.stem}_shell.npz"), [])
               for label, src in bases if (work / f"{src.stem}_shell.npz").exists()]
    for shell, source, size in shells:
        stem = Path(source).stem
        out = work / f"map_{stem}.stl"
        rep = work / f"map_{stem}.json"
        wall, peak, code, err, cpu, load = _timed(
            GEOTEX + ["map", "--tiles", "studs", "--shell", source, "-o", str(out),
                      "--report", str(rep)] + size, work)
        row = {"shell": shell, "wall": wall, "peak": peak, "code": code, "err": err,
               "cpu": cpu, "load": load}
        if code == 0:
            doc = json.loads(rep.read_text())
            row.update(faces=doc["stats"]["faces"], seconds=doc["seconds"],
                       retries=doc["stats"]["union_retries"])
        rows_map.append(row)
        print(row, flush=True)
    demo = _timed(GEOTEX + ["demo", "-o", str(work / "demo")], work)
    load = os.getloadavg()
    lines = [
        "# The main job end to end",
        "",
        f"Run {time.strftime('%Y-%m-%d %H:%M')} on {platform.machine()}, {os.cpu_count()} cores "
        f"(1-min load {start_load:.1f} before the first run and {load[0]:.1f} at the end"
        f"{'' if start_load < 0.5 else ': other jobs share the machine'}), Python "
        f"{platform.python_version()}; `python benchmarks/bench_main_job.py`. Each command "
        "runs in its own process; peak memory from `/usr/bin/time -v`. Tile set `studs` "
        "(16 tiles, isotropic), parts scaled to 80 mm. Targets (issue #13): one-shot "
        "`geotex texture` of a ~15k-face base <= 5 s at ~300k output faces and <= 10 s at "
        "~1M, peak <= 1.5 GB at 1M; `geotex map` <= 3 s at 300k; `geotex demo` <= 10 s.",
        "",
        "## geotex texture (one shot: read, shell, map, union, float32 check, verified STL write)",
        "",
        "Stages (s): read+shell / assign / map / union / validate (float32 rebuild + the one "
        "full check) / write (STL written, read back, compared). Peer: manifold3d's plain "
        "batch union of the same base and elements (same operands, no fold test, no check).",
        "",
        "| base | tile mm | quads | output faces | wall s | CPU s | load | peak MB | stages s | "
        "retries | peer union s | check on file |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows_texture:
        if r["code"]:
            lines.append(f"| {r['base']} | | | | {r['wall']:.1f} | {r['cpu']:.1f} | "
                         f"{r['load']:.1f} | {r['peak']:.0f} | failed "
                         f"(exit {r['code']}): {r['err']} | | | |")
            continue
        s = r["seconds"]
        st = " / ".join(f"{s.get(k, 0):.2f}" for k in ("read+shell", "assign", "map", "union",
                                                        "validate", "write"))
        lines.append(f"| {r['base']} | {r['tile']:.3g} | {r['quads']} | {r['faces']:,} | "
                     f"**{r['wall']:.1f}** | {r['cpu']:.1f} | {r['load']:.1f} | "
                     f"{r['peak']:.0f} | {st} | {r['retries']} | "
                     f"{r['peer_union']:.2f} | {r['check']} |")
    lines += ["", "## geotex map (a ready shell, no shell building)", "",
              "Catalog shells at 80 mm, and the shells of the ~15k-face bases above at their "
              "default tile size (saved by `geotex texture --shell-out`, at print size).", "",
              "| shell | output faces | wall s | CPU s | load | peak MB | stages s (assign / map / "
              "union / validate / write) | retries |", "|---|---|---|---|---|---|---|---|"]
    for r in rows_map:
        if r["code"]:
            lines.append(f"| {r['shell']} | | {r['wall']:.1f} | {r['cpu']:.1f} | "
                         f"{r['load']:.1f} | {r['peak']:.0f} | failed "
                         f"(exit {r['code']}): {r['err']} | |")
            continue
        s = r["seconds"]
        st = " / ".join(f"{s.get(k, 0):.2f}" for k in ("assign", "map", "union", "validate",
                                                        "write"))
        lines.append(f"| {r['shell']} | {r['faces']:,} | **{r['wall']:.1f}** | "
                     f"{r['cpu']:.1f} | {r['load']:.1f} | {r['peak']:.0f} | {st} | "
                     f"{r['retries']} |")
    lines += ["", "## geotex demo", "",
              f"`geotex demo` (Spot at 80 mm, studs, STL + 3MF + picture + report): "
              f"**{demo[0]:.1f} s** wall, {demo[4]:.1f} s CPU (1-min load {demo[5]:.1f} "
              f"before it), peak {demo[1]:.0f} MB, exit {demo[2]}.", ""]
    write_keeping_hand_sections(args.out, "\n".join(lines) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
