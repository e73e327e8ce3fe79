"""Benchmark: ``geotex displace`` against Blender's displace modifier and BumpMesh (issue #23).

Inputs (the issue's): Spot (Keenan Crane, public domain) scaled so its
largest extent is 89 mm, and a closed cylinder r 20 x h 40 mm with 67,600
faces (:func:`geotex.mesh.primitives.closed_cylinder`, 200 x 130 side grid,
20 cap rings); the bricks depth map of ``../shared/data/texture_exemplars/
heightmaps`` (1000 x 1000, white high), 20 mm per image tile, 1 mm depth,
about 2M output triangles.

Each tool runs as a fresh process on the same STL input and writes an STL;
wall time and peak memory (``/usr/bin/time -v``, maximum resident set size)
cover the whole process (start-up, read, work, write):

* ``geotex displace`` (CLI), ``triplanar`` (the default) and ``planar-xy``
  (the same projection as Blender's), the edge length chosen beforehand (not
  timed) so the refined mesh has 1.8M-2.4M faces; the time includes the
  printability verdict on the stored coordinates and the verified write
  (write, read back, compare).
* Blender 3.4 (Debian package), headless: STL import, Subdivision Surface
  modifier (simple, ``levels`` so a triangle mesh gets 1.6M-2.3M
  triangles: each level-1 triangle becomes 3 quads, each further level
  multiplies by 4), Displace modifier (image texture, object coordinates of
  an empty scaled to one tile = 20 mm, i.e. a planar x-y projection like
  ``planar-xy``, strength 1 mm, mid-level 0, along vertex normals), STL
  export with modifiers applied.
* BumpMesh (CNCKitchen/stlTexturizer, AGPL-3.0-only), its export pipeline
  run headless in Node by ``benchmarks/bumpmesh_displace.mjs`` (geotex's own
  driver; BumpMesh's modules are loaded from an external checkout given with
  ``--bumpmesh DIR``, never copied into geotex; the row is skipped with a note
  when the option is missing or the directory is not a prepared checkout, see
  the driver's header for the set-up). Settings: the app's defaults except
  triplanar mapping, 20 mm tile, 1 mm amplitude, no bottom angle mask (geotex
  runs with ``--mask-bottom 0`` and Blender displaces everything too), and
  either (a) refine length = geotex's edge length and a 2,000,000 triangle
  target ("2M") or (b) the app's default resolution (refine length = diagonal
  / 250, 750,000 triangle target). The depth map is handed over as an 8-bit
  grey PNG (converted from the JPEG before timing; the browser decodes it
  through a canvas).

Each process's CPU seconds (user + system, ``/usr/bin/time -v``) are recorded
beside wall seconds, with the 1-minute load average when it started: the
machine is shared.

Verdicts on every written file: ``geotex check`` (the full check, including
manifold3d), ``prusa-slicer --info`` and ``admesh``.

Run:  python benchmarks/bench_displace.py [--repeat 1] [--bumpmesh /tmp/bumpmesh]
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from handkept import write_keeping_hand_sections
from geotex.check.report import check_mesh
from geotex.check.slicers import (admesh_report, admesh_verdict, prusaslicer_info,
                                   prusaslicer_verdict)
from geotex.io import read_mesh, write_mesh
from geotex.mesh.primitives import closed_cylinder
from geotex.mesh.record import Mesh
from geotex.relief import refined_by_edge_splits

HERE = Path(__file__).resolve().parent
SHARED = next((p / "shared" / "data" for p in HERE.parents[1:3]
               if (p / "shared" / "data").is_dir()), HERE.parents[1] / "shared" / "data")
SPOT = SHARED / "base" / "spot_odedstein.obj"
BRICKS = SHARED / "texture_exemplars" / "heightmaps" / "godot_texture_bricks_depth.jpg"
TILE_MM = 20.0
DEPTH_MM = 1.0
TARGET = 2_000_000
BUMPMESH_DRIVER = HERE / "bumpmesh_displace.mjs"

BLENDER_SCRIPT = r"""
import bpy, sys
argv = sys.argv[sys.argv.index("--") + 1:]
src, img, out, levels, tile, depth = argv[0], argv[1], argv[2], int(argv[3]), float(argv[4]), float(argv[5])
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_mesh.stl(filepath=src)
obj = bpy.context.selected_objects[0]
bpy.ops.object.empty_add(location=(0, 0, 0))
empty = bpy.context.object
empty.scale = (tile / 2, tile / 2, tile / 2)      # texture space [-1, 1] -> one tile
bpy.context.view_layer.objects.active = obj
sub = obj.modifiers.new("sub", "SUBSURF")
sub.subdivision_type = "SIMPLE"
sub.levels = levels
sub.render_levels = levels
tex = bpy.data.textures.new("bricks", "IMAGE")
tex.image = bpy.data.images.load(img)
tex.extension = "REPEAT"
dis = obj.modifiers.new("dis", "DISPLACE")
dis.texture = tex
dis.texture_coords = "OBJECT"
dis.texture_coords_object = empty
dis.strength = depth
dis.mid_level = 0.0
dis.direction = "NORMAL"
for o in bpy.context.scene.objects:
    o.select_set(o == obj)
bpy.context.view_layer.objects.active = obj
bpy.ops.export_mesh.stl(filepath=out, use_selection=True, use_mesh_modifiers=True, ascii=False)
"""


def timed_process(cmd, env=None, cwd=None):
    """Wall seconds, peak RSS (MB) and CPU seconds of a command, via /usr/bin/time -v."""
    p = subprocess.run(["/usr/bin/time", "-v", *cmd], capture_output=True, text=True, env=env,
                       cwd=cwd)
    if p.returncode not in (0, 1):
        raise RuntimeError(f"{cmd[0]} failed ({p.returncode}): {p.stderr[-2000:]}")
    wall = re.search(r"Elapsed \(wall clock\) time.*: (?:(\d+):)?(\d+):([\d.]+)", p.stderr)
    h, m, s = wall.groups()
    secs = (int(h) * 3600 if h else 0) + int(m) * 60 + float(s)
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr).group(1))
    cpu = sum(float(re.search(rf"{k} time \(seconds\): ([\d.]+)", p.stderr).group(1))
              for k in ("User", "System"))
    p.cpu_seconds = cpu
    return secs, rss / 1024.0, p


def bumpmesh_ready(path):
    """None when ``path`` is a prepared BumpMesh checkout, else why it is skipped."""
    if path is None:
        return "BumpMesh not run: no --bumpmesh DIR given"
    d = Path(path)
    missing = [x for x in ("js/exportPipeline.js", "node_modules/three", "node_modules/fflate",
                           "node_modules/pngjs") if not (d / x).exists()]
    if missing:
        return f"BumpMesh not run: {d} lacks {', '.join(missing)}"
    if subprocess.run(["node", "--version"], capture_output=True).returncode != 0:
        return "BumpMesh not run: node is not installed"
    return None


def bumpmesh_version(path):
    try:
        txt = (Path(path) / "js" / "version.js").read_text()
        return re.search(r"['\"](\d+\.\d+\.\d+)['\"]", txt).group(1)
    except Exception:  # noqa: BLE001
        return "?"


def inputs(tmp: Path):
    Vc, Fc = closed_cylinder(20.0, 40.0, n_theta=200, n_height=130, n_cap_rings=20)
    cyl = tmp / "cylinder.stl"
    write_mesh(cyl, Mesh(Vc, Fc))
    m = read_mesh(SPOT)
    V = m.vertices - m.vertices.min(axis=0)
    V = V * (89.0 / float(np.ptp(V, axis=0).max()))
    spot = tmp / "spot89.stl"
    write_mesh(spot, Mesh(V, m.faces))
    return {"spot": spot, "cylinder": cyl}


def edge_for_target(path, target=TARGET):
    """Edge length whose edge-split refinement has 0.9-1.2 x target faces (bisection)."""
    m = read_mesh(path)
    V, F = m.vertices, m.faces
    area = 0.5 * np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]),
                                axis=1).sum()
    lo, hi = np.sqrt(area / (0.5 * target)), np.sqrt(area / (0.05 * target))
    best = None
    for _ in range(10):
        L = np.sqrt(lo * hi)
        n = refined_by_edge_splits(V, F, L, max_faces=4 * target).faces.shape[0]
        if best is None or abs(np.log(n / target)) < abs(np.log(best[1] / target)):
            best = (L, n)
        if 0.9 * target <= n <= 1.2 * target:
            break
        if n > target:
            lo = L
        else:
            hi = L
    return float(best[0]), int(best[1]), int(F.shape[0])


CLOSEUPS = []


def closeup(path, name, label):
    """Keep the faces near the close-up point (cylinder cap edge, Spot's flank)."""
    from geotex.mesh.topology import compacted

    m = read_mesh(path)
    V, F = m.vertices, m.faces
    if name == "cylinder":
        c, r = np.array([20 / np.sqrt(2), 20 / np.sqrt(2), 40.0]), 7.0
    else:
        V = V[:, [0, 2, 1]] * np.array([1.0, -1.0, 1.0])      # Spot is y-up: show it z-up
        lo, hi = V.min(axis=0), V.max(axis=0)
        c, r = np.array([hi[0], 0.5 * (lo[1] + hi[1]), lo[2] + 0.45 * (hi[2] - lo[2])]), 12.0
        c = V[np.argmin(np.linalg.norm(V - c, axis=1))]
    sel = np.linalg.norm(V[F].mean(axis=1) - c, axis=1) < r
    Vc, Fc = compacted(V, F[sel])
    CLOSEUPS.append((name, label, Vc, Fc))


def verdicts(path):
    m = read_mesh(path)
    rep = check_mesh(m.vertices, m.faces)
    out = {"triangles": int(m.faces.shape[0]), "geotex_check": bool(rep.printable),
           "geotex_reasons": rep.reasons[:3]}
    try:
        v = prusaslicer_verdict(prusaslicer_info(path))
        out["prusaslicer"] = v
        out["prusaslicer_ok"] = bool(v["ok"])
    except Exception as exc:  # noqa: BLE001 - record the tool's failure
        out["prusaslicer"] = f"failed: {exc}"
        out["prusaslicer_ok"] = False
    try:
        v = admesh_verdict(admesh_report(path))
        out["admesh"] = v
        out["admesh_ok"] = bool(v["ok"])
    except Exception as exc:  # noqa: BLE001
        out["admesh"] = f"failed: {exc}"
        out["admesh_ok"] = False
    return out


def blender_levels(faces):
    best = None
    for L in range(1, 7):
        tris = 2 * 3 * 4 ** (L - 1) * faces
        if best is None or abs(np.log(tris / TARGET)) < abs(np.log(best[1] / TARGET)):
            best = (L, tris)
    return best


def run_row(rows, cmd, base_row, out, closeup_label, *, env=None, cwd=None, repeat=1,
            name=None, parse=None):
    """Run ``cmd`` ``repeat`` times as fresh processes; the last run's file gets the verdicts."""
    for r in range(repeat):
        load1 = os.getloadavg()[0]
        secs, mb, p = timed_process(cmd, env, cwd)
        row = dict(base_row, seconds=secs, cpu_seconds=round(p.cpu_seconds, 2), peak_mb=mb,
                   exit=p.returncode, run=r, load1_at_start=round(load1, 2))
        if parse is not None:
            row.update(parse(p))
        if r == repeat - 1 and out.exists():
            row.update(verdicts(out))
            closeup(out, name, closeup_label)
        rows.append(row)
        print(json.dumps({k: v for k, v in row.items() if k not in ("prusaslicer", "admesh")}),
              flush=True)


def parse_bumpmesh(p):
    try:
        doc = json.loads(p.stdout.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return {"bumpmesh_error": p.stderr[-500:]}
    return {"stages": doc["stages"], "refine_mm": doc["refine_mm"],
            "max_triangles": doc["max_triangles"], "stage_triangles": doc["stage_triangles"],
            "bumpmesh_repair": doc["repair"]}


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--markdown-only", action="store_true",
                    help="rewrite results/displace.md from results/displace.json")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--no-blender", action="store_true")
    ap.add_argument("--bumpmesh", metavar="DIR", default=None,
                    help="prepared stlTexturizer checkout (see benchmarks/bumpmesh_displace.mjs);"
                         " BumpMesh is skipped with a note without it")
    args = ap.parse_args(argv)
    if args.markdown_only:
        doc = json.loads((HERE / "results" / "displace.json").read_text())
        write_markdown(HERE / "results" / "displace.md", doc["meta"], doc["rows"])
        return
    env = dict(os.environ, PYTHONPATH=str(HERE.parent))
    skip_bumpmesh = bumpmesh_ready(args.bumpmesh)
    if skip_bumpmesh:
        print(skip_bumpmesh, file=sys.stderr, flush=True)
    bm_version = None if skip_bumpmesh else bumpmesh_version(args.bumpmesh)
    rows = []
    with tempfile.TemporaryDirectory() as td:
        tmp = Path(td)
        bases = inputs(tmp)
        bricks_png = tmp / "bricks.png"
        if not skip_bumpmesh:
            from PIL import Image

            Image.open(BRICKS).convert("L").save(bricks_png)
        for name, base in bases.items():
            L, n_ref, n_base = edge_for_target(base)
            runs = [("geotex displace (triplanar)", "triplanar"),
                    ("geotex displace (planar-xy)", "planar-xy")]
            for label, mapping in runs:
                out = tmp / f"{name}_{mapping}.stl"
                rep = tmp / f"{name}_{mapping}.json"
                cmd = [sys.executable, "-m", "geotex", "displace", str(base), "--image",
                       str(BRICKS), "--depth", str(DEPTH_MM), "--mapping", mapping,
                       "--scale-u", str(TILE_MM), "--edge-mm", f"{L:.6g}",
                       "--mask-bottom", "0", "-o", str(out), "--report", str(rep)]

                def parse_geotex(p, rep=rep):
                    doc = json.loads(rep.read_text())["stats"] if rep.exists() else {}
                    return {"stages": doc.get("seconds", {}),
                            "relief_reduced_rounds": doc.get("relief_reduced_rounds")}

                run_row(rows, cmd, {"base": name, "base_faces": n_base, "tool": label,
                                    "edge_mm": L}, out, label, env=env, repeat=args.repeat,
                        name=name, parse=parse_geotex)
            if not args.no_blender:
                levels, tris = blender_levels(n_base)
                out = tmp / f"{name}_blender.stl"
                script = tmp / "blender_displace.py"
                script.write_text(BLENDER_SCRIPT)
                cmd = ["blender", "-b", "--factory-startup", "--python", str(script), "--",
                       str(base), str(BRICKS), str(out), str(levels), str(TILE_MM),
                       str(DEPTH_MM)]
                run_row(rows, cmd, {"base": name, "base_faces": n_base,
                                    "tool": f"Blender {blender_version()} displace modifier "
                                            "+ STL export",
                                    "subdivision_levels": levels}, out,
                        "Blender displace modifier", repeat=args.repeat, name=name)
            if not skip_bumpmesh:
                for tag, refine, maxtri in (("2M", f"{L:.6g}", str(TARGET)),
                                            ("default resolution", "default", "default")):
                    out = tmp / f"{name}_bumpmesh_{tag.split()[0]}.stl"
                    cmd = ["node", str(BUMPMESH_DRIVER), "--bumpmesh", str(args.bumpmesh),
                           "--stl", str(base), "--image", str(bricks_png), "--out", str(out),
                           "--tile-mm", str(TILE_MM), "--depth-mm", str(DEPTH_MM),
                           "--mapping", "5", "--refine-mm", refine, "--max-triangles", maxtri]
                    label = f"BumpMesh {bm_version} pipeline in Node, triplanar, {tag}"
                    run_row(rows, cmd, {"base": name, "base_faces": n_base, "tool": label},
                            out, f"BumpMesh {tag}", repeat=args.repeat, name=name,
                            parse=parse_bumpmesh)
    if CLOSEUPS:
        render_closeups(HERE.parent / "docs" / "gallery" / "displace_bench_closeups.png")
    load = os.getloadavg()
    meta = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "machine": f"{platform.machine()}, {os.cpu_count()} cores, shared",
            "load_average_at_end": [round(x, 2) for x in load],
            "tile_mm": TILE_MM, "depth_mm": DEPTH_MM, "target_triangles": TARGET,
            "bumpmesh": skip_bumpmesh or f"stlTexturizer {bm_version} from {args.bumpmesh}"}
    res = HERE / "results"
    (res / "displace.json").write_text(json.dumps({"meta": meta, "rows": rows}, indent=2,
                                                  default=str))
    write_markdown(res / "displace.md", meta, rows)


def render_closeups(path):
    """One row of close-ups per base (every tool side by side), rows stacked in one PNG."""
    from PIL import Image

    from geotex.render import Panel, render_panels

    path.parent.mkdir(parents=True, exist_ok=True)
    names = list(dict.fromkeys(n for n, *_ in CLOSEUPS))
    strips = []
    with tempfile.TemporaryDirectory() as td:
        for n in names:
            panels = [Panel(V, F, color="#c9b38f", title=f"{n}: {label}")
                      for m, label, V, F in CLOSEUPS if m == n]
            strip = render_panels(panels, Path(td) / f"{n}.png", size=(420, 420), up="z")
            strips.append(Image.open(strip).convert("RGB"))
    W = max(im.width for im in strips)
    sheet = Image.new("RGB", (W, sum(im.height for im in strips)), "white")
    y = 0
    for im in strips:
        sheet.paste(im, (0, y))
        y += im.height
    sheet.save(path)


def blender_version():
    try:
        p = subprocess.run(["blender", "--version"], capture_output=True, text=True, timeout=60)
        return p.stdout.split()[1]
    except Exception:  # noqa: BLE001
        return "?"


def _median_by(rows, pred, key="seconds"):
    vals = [r[key] for r in rows if pred(r) and r.get(key) is not None]
    return float(np.median(vals)) if vals else None


def targets(rows):
    """Per base: best geotex speed-up over Blender and over BumpMesh (2M), geotex peak memory."""
    out = {}
    for base in dict.fromkeys(r["base"] for r in rows):
        mine = [r for r in rows if r["base"] == base]
        geo = {t: _median_by(mine, lambda r, t=t: r["tool"] == t)
               for t in dict.fromkeys(r["tool"] for r in mine if r["tool"].startswith("geotex"))}
        geo_cpu = {t: _median_by(mine, lambda r, t=t: r["tool"] == t, "cpu_seconds") for t in geo}
        best = min(geo, key=geo.get) if geo else None
        blender = _median_by(mine, lambda r: r["tool"].startswith("Blender"))
        bump = _median_by(mine, lambda r: r["tool"].startswith("BumpMesh") and r["tool"].endswith("2M"))
        bump_cpu = _median_by(mine, lambda r: r["tool"].startswith("BumpMesh")
                              and r["tool"].endswith("2M"), "cpu_seconds")
        blender_cpu = _median_by(mine, lambda r: r["tool"].startswith("Blender"), "cpu_seconds")
        peak = max((r["peak_mb"] for r in mine if r["tool"].startswith("geotex")), default=None)
        out[base] = {
            "fastest_geotex": best, "geotex_seconds": geo.get(best) if best else None,
            "vs_blender": blender / geo[best] if best and blender else None,
            "vs_blender_cpu": (blender_cpu / geo_cpu[best]
                               if best and blender_cpu and geo_cpu.get(best) else None),
            "vs_bumpmesh": bump / geo[best] if best and bump else None,
            "vs_bumpmesh_cpu": (bump_cpu / geo_cpu[best]
                                if best and bump_cpu and geo_cpu.get(best) else None),
            "geotex_peak_mb": peak}
    return out


def write_markdown(path, meta, rows):
    bm = meta.get("bumpmesh", "BumpMesh not run (older run)")
    lines = ["# geotex displace vs Blender's displace modifier and BumpMesh (issue #23)", "",
             f"Run {meta['date']} on {meta['machine']} (load average at the end "
             f"{meta['load_average_at_end']}; other jobs shared the 2 cores, so wall times "
             "are inflated and CPU seconds (user + system of the process) are given beside "
             "them; the 1-minute load average when each process started is in the table). "
             f"Bricks depth map, {meta['tile_mm']:g} mm per tile, {meta['depth_mm']:g} mm depth, "
             "STL written, every tool a fresh process on the same STL input. "
             f"BumpMesh: {bm}. Produced by `benchmarks/bench_displace.py`.", "",
             "| base | tool | triangles | wall (s) | CPU (s) | load 1 min | Blender / this "
             "| BumpMesh 2M / this | peak memory (MB) | geotex check | PrusaSlicer | admesh "
             "| stages (s) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    blender = {r["base"]: r["seconds"] for r in rows if r["tool"].startswith("Blender")}
    bump = {r["base"]: r["seconds"] for r in rows
            if r["tool"].startswith("BumpMesh") and r["tool"].endswith("2M")}
    ok = lambda x: "-" if x is None else ("yes" if x else "NO")  # noqa: E731
    for r in rows:
        b, m = blender.get(r["base"]), bump.get(r["base"])
        rb = f"{b / r['seconds']:.2f}" if b and not r["tool"].startswith("Blender") else ""
        rm = (f"{m / r['seconds']:.2f}" if m and not (r["tool"].startswith("BumpMesh")
                                                       and r["tool"].endswith("2M")) else "")
        st = ", ".join(f"{k} {v:.1f}" for k, v in r.get("stages", {}).items())
        if r.get("relief_reduced_rounds"):
            st += f"; relief lowered in {r['relief_reduced_rounds']} round(s)"
        if r.get("refine_mm") is not None:
            st += f"; refine {r['refine_mm']:.3g} mm, target {r['max_triangles']}"
        cpu = f"{r['cpu_seconds']:.1f}" if r.get("cpu_seconds") is not None else "?"
        load = f"{r['load1_at_start']:.1f}" if r.get("load1_at_start") is not None else "?"
        lines.append(f"| {r['base']} ({r['base_faces']} faces) | {r['tool']} | "
                     f"{r.get('triangles', '?')} | {r['seconds']:.1f} | {cpu} | {load} | {rb} | "
                     f"{rm} | {r['peak_mb']:.0f} | {ok(r.get('geotex_check'))} | "
                     f"{ok(r.get('prusaslicer_ok'))} | {ok(r.get('admesh_ok'))} | {st} |")
    lines += ["", "## Issue #23 targets (fastest geotex mapping per base, medians of the runs)", "",
              "| base | fastest geotex | wall (s) | x Blender (wall / CPU) | target >= 4.5 "
              "| x BumpMesh 2M (wall / CPU) | target >= 15 | geotex peak (MB) | target < 1024 |",
              "|---|---|---|---|---|---|---|---|---|"]
    f = lambda x: "-" if x is None else f"{x:.2f}"  # noqa: E731
    met = lambda x, t, ge=True: "-" if x is None else (  # noqa: E731
        ("met" if (x >= t if ge else x < t) else "NOT met"))
    for base, t in targets(rows).items():
        lines.append(f"| {base} | {t['fastest_geotex']} | {f(t['geotex_seconds'])} | "
                     f"{f(t['vs_blender'])} / {f(t['vs_blender_cpu'])} | "
                     f"{met(t['vs_blender'], 4.5)} | {f(t['vs_bumpmesh'])} / "
                     f"{f(t['vs_bumpmesh_cpu'])} | {met(t['vs_bumpmesh'], 15)} | "
                     f"{f(t['geotex_peak_mb'])} | {met(t['geotex_peak_mb'], 1024, ge=False)} |")
    lines += ["", "PrusaSlicer and admesh verdicts are `geotex.check.slicers.prusaslicer_verdict` / "
              "`admesh_verdict` (manifold, nothing repaired, one part, positive volume). "
              "geotex check is "
              "the full `check_mesh` (self-intersections and manifold3d included) on the file "
              "as read back.", ""]
    write_keeping_hand_sections(path, "\n".join(lines))


if __name__ == "__main__":
    main()
