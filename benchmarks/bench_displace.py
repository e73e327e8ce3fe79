"""Benchmark: ``geotex displace`` against Blender's displace modifier (issue #23).

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

Verdicts on every written file: ``geotex check`` (the full check, including
manifold3d), ``prusa-slicer --info`` and ``admesh``.

Run:  python benchmarks/bench_displace.py [--repeat 1]
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


def timed_process(cmd, env=None):
    """Wall seconds and peak RSS (MB) of a command, via /usr/bin/time -v."""
    p = subprocess.run(["/usr/bin/time", "-v", *cmd], capture_output=True, text=True, env=env)
    if p.returncode not in (0, 1):
        raise RuntimeError(f"{cmd[0]} failed ({p.returncode}): {p.stderr[-2000:]}")
    wall = re.search(r"Elapsed \(wall clock\) time.*: (?:(\d+):)?(\d+):([\d.]+)", p.stderr)
    h, m, s = wall.groups()
    secs = (int(h) * 3600 if h else 0) + int(m) * 60 + float(s)
    rss = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr).group(1))
    return secs, rss / 1024.0, p


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


def main(argv=None):
    ap = argparse.ArgumentParser()
    ap.add_argument("--markdown-only", action="store_true",
                    help="rewrite results/displace.md from results/displace.json")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--no-blender", action="store_true")
    args = ap.parse_args(argv)
    if args.markdown_only:
        doc = json.loads((HERE / "results" / "displace.json").read_text())
        write_markdown(HERE / "results" / "displace.md", doc["meta"], doc["rows"])
        return
    env = dict(os.environ, PYTHONPATH=str(HERE.parent))
    rows = []
    with tempfile.TemporaryDirectory() as td:
        tmp = Path(td)
        bases = inputs(tmp)
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
                for r in range(args.repeat):
                    secs, mb, p = timed_process(cmd, env)
                    doc = json.loads(rep.read_text())["stats"] if rep.exists() else {}
                    stages = doc.get("seconds", {})
                    row = {"base": name, "base_faces": n_base, "tool": label, "seconds": secs,
                           "peak_mb": mb, "exit": p.returncode, "stages": stages,
                           "edge_mm": L, "run": r,
                           "relief_reduced_rounds": doc.get("relief_reduced_rounds")}
                    if r == args.repeat - 1 and out.exists():
                        row.update(verdicts(out))
                        closeup(out, name, label)
                    rows.append(row)
                    print(json.dumps({k: v for k, v in row.items()
                                      if k not in ("prusaslicer", "admesh")}), flush=True)
            if not args.no_blender:
                levels, tris = blender_levels(n_base)
                out = tmp / f"{name}_blender.stl"
                script = tmp / "blender_displace.py"
                script.write_text(BLENDER_SCRIPT)
                cmd = ["blender", "-b", "--factory-startup", "--python", str(script), "--",
                       str(base), str(BRICKS), str(out), str(levels), str(TILE_MM),
                       str(DEPTH_MM)]
                for r in range(args.repeat):
                    secs, mb, p = timed_process(cmd)
                    row = {"base": name, "base_faces": n_base,
                           "tool": f"Blender {blender_version()} displace modifier + STL export",
                           "seconds": secs, "peak_mb": mb, "exit": p.returncode,
                           "subdivision_levels": levels, "run": r}
                    if r == args.repeat - 1 and out.exists():
                        row.update(verdicts(out))
                        closeup(out, name, "Blender displace modifier")
                    rows.append(row)
                    print(json.dumps({k: v for k, v in row.items()
                                      if k not in ("prusaslicer", "admesh")}), flush=True)
    if CLOSEUPS:
        from geotex.render import Panel, render_panels

        panels = [Panel(V, F, color="#c9b38f", title=f"{n}: {label}")
                  for n, label, V, F in CLOSEUPS]
        gallery = HERE.parent / "docs" / "gallery"
        gallery.mkdir(parents=True, exist_ok=True)
        render_panels(panels, gallery / "displace_bench_closeups.png", size=(520, 520),
                      up="z")
    load = os.getloadavg()
    meta = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "machine": f"{platform.machine()}, {os.cpu_count()} cores, shared",
            "load_average_at_end": [round(x, 2) for x in load],
            "tile_mm": TILE_MM, "depth_mm": DEPTH_MM, "target_triangles": TARGET}
    res = HERE / "results"
    (res / "displace.json").write_text(json.dumps({"meta": meta, "rows": rows}, indent=2,
                                                  default=str))
    write_markdown(res / "displace.md", meta, rows)


def blender_version():
    try:
        p = subprocess.run(["blender", "--version"], capture_output=True, text=True, timeout=60)
        return p.stdout.split()[1]
    except Exception:  # noqa: BLE001
        return "?"


def write_markdown(path, meta, rows):
    lines = ["# geotex displace vs Blender's displace modifier (issue #23)", "",
             f"Run {meta['date']} on {meta['machine']} (load average at the end "
             f"{meta['load_average_at_end']}: other jobs shared the 2 cores, so absolute times "
             "are inflated; both tools ran in the same conditions, interleaved). "
             f"Bricks depth map, {meta['tile_mm']:g} mm per tile, {meta['depth_mm']:g} mm depth, "
             "STL written. Produced by `benchmarks/bench_displace.py`.", "",
             "| base | tool | triangles | time (s) | Blender time / this time | peak memory (MB) "
             "| geotex check "
             "| PrusaSlicer | admesh | geotex stages (s) |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    blender = {r["base"]: r["seconds"] for r in rows if r["tool"].startswith("Blender")}
    for r in rows:
        b = blender.get(r["base"])
        ratio = f"{b / r['seconds']:.2f}" if b and not r["tool"].startswith("Blender") else ""
        st = ", ".join(f"{k} {v:.1f}" for k, v in r.get("stages", {}).items())
        if r.get("relief_reduced_rounds"):
            st += f"; relief lowered in {r['relief_reduced_rounds']} round(s)"
        ok = lambda x: "-" if x is None else ("yes" if x else "NO")  # noqa: E731
        lines.append(f"| {r['base']} ({r['base_faces']} faces) | {r['tool']} | "
                     f"{r.get('triangles', '?')} | {r['seconds']:.1f} | {ratio} | "
                     f"{r['peak_mb']:.0f} | {ok(r.get('geotex_check'))} | "
                     f"{ok(r.get('prusaslicer_ok'))} | {ok(r.get('admesh_ok'))} | {st} |")
    lines += ["", "PrusaSlicer and admesh verdicts are `geotex.check.slicers.prusaslicer_verdict` / "
              "`admesh_verdict` (manifold, nothing repaired, one part, positive volume). "
              "geotex check is "
              "the full `check_mesh` (self-intersections and manifold3d included) on the file "
              "as read back.", ""]
    Path(path).write_text("\n".join(lines))


if __name__ == "__main__":
    main()
