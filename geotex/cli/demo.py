"""``geotex demo``: the main job on bundled data, writing real files.

Spot the cow (bundled) is turned to print orientation and scaled to print
size, its polycube shell is built, a bundled geometric Wang tile set is laid
over it, the elements are united with the body into one solid, the solid is
checked and written as STL and 3MF, with a picture and a JSON report.
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from geotex.cli._common import EXIT_NOT_PRINTABLE, EXIT_OK, UsageError, preload_compiled

HELP = "texture a bundled model with a bundled tile set and write a printable solid"

#: What the demo uses: bundled base, catalog tile set, tiles across the model.
DEMO_BASE = "spot"
DEMO_TILES = "studs"
DEMO_TILES_ACROSS = 15


def register(sub):
    p = sub.add_parser("demo", help=HELP, description=HELP + ".")
    p.add_argument("-o", "--output-dir", default="geotex-demo",
                   help="folder for the results (default ./geotex-demo)")
    p.add_argument("--size-mm", type=float, default=80.0,
                   help="largest extent of the printed model in millimetres (default 80)")
    p.add_argument("--tiles", default=DEMO_TILES,
                   help=f"tile set: catalog name or file (default {DEMO_TILES})")
    p.add_argument("--seed", type=int, default=0, help="seed of the tile layout (default 0)")
    p.set_defaults(run=run)


def print_ready(V: np.ndarray, *, size_mm: float, y_up: bool) -> np.ndarray:
    """Return ``V`` rotated to z-up (if y-up), scaled to ``size_mm`` and set on z = 0.

    A y-up model is turned by (x, y, z) -> (-x, z, y), a proper rotation that
    also faces its +z front towards the picture's default camera (-y side).
    """
    P = V[:, [0, 2, 1]] * np.array([-1.0, 1.0, 1.0]) if y_up else V.copy()
    lo, hi = P.min(axis=0), P.max(axis=0)
    P = (P - np.array([(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, lo[2]]))
    return P * (size_mm / float(np.max(hi - lo)))


def run(args) -> int:
    from geotex.render import background_renderer
    from geotex.tiles.catalog import load_named

    out = Path(args.output_dir)
    if out.exists() and not out.is_dir():
        raise UsageError(f"{out}: exists and is not a folder")
    if not (10.0 <= args.size_mm <= 1000.0):
        raise UsageError(f"--size-mm {args.size_mm}: choose a size between 10 and 1000 mm")
    if args.seed < 0:
        raise UsageError(f"--seed {args.seed}: give a non-negative integer")
    preload_compiled()
    tiles = load_named(args.tiles)
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    with background_renderer() as painter:
        return _run(args, out, tiles, start, painter)


def _run(args, out, tiles, start, painter) -> int:
    from geotex.data import sample_path
    from geotex.errors import NotPrintableError
    from geotex.io import read_mesh
    from geotex.io.atomic import atomic_output
    from geotex.mapping import MAP_PROGRESS, textured_solid
    from geotex.printing import StagedWrite, export_printable
    from geotex.progress import stage_bar
    from geotex.render import Panel, render_panels
    from geotex.shells import SHELL_STAGES, build_shell

    base = read_mesh(sample_path(DEMO_BASE))
    V = print_ready(base.vertices, size_mm=args.size_mm, y_up=True)
    tile_mm = args.size_mm / DEMO_TILES_ACROSS
    name = f"{DEMO_BASE}_{tiles.name}"
    picture_path = out / f"{name}.png"
    pictures = []                       # (future, hidden file) of each solid drawn
    with stage_bar(len(SHELL_STAGES) + len(MAP_PROGRESS), "geotex demo") as bar:
        shell = build_shell(V, base.faces, tile_size=tile_mm, name=DEMO_BASE,
                            source=f"sample:{DEMO_BASE}", progress=bar)
        panels = [
            Panel(V, base.faces, color="#d9c7a3", title=f"{DEMO_BASE}: {base.n_faces} "
                  f"faces, {args.size_mm:g} mm"),
            Panel(shell.polycube.Y, shell.polycube.F, scalars=shell.polycube.layout.quad_label[
                shell.polycube.layout.face_quad], cmap="Set2",
                title=f"polycube map: {shell.n_quads} tiles of {tile_mm:.3g} mm")]

        def draw(Vs, Fs):
            # the solid about to be judged is drawn in the worker process while
            # the check runs here (a retried union draws its new solid); the
            # picture takes its name only once the solid is printable
            for future, _ in pictures:
                future.cancel()
            hidden = out / f".{name}.{os.getpid()}.{len(pictures)}.png"
            pictures.append((painter.submit(render_panels, panels + [
                Panel(Vs, Fs, color="#c9b38f", title=f"{tiles.name}: {Fs.shape[0]} faces, "
                      "printable")], hidden, size=(700, 700)), hidden))

        with StagedWrite(out / f"{name}.stl", name=name) as staged:
            def judged(Vs, Fs):
                staged(Vs, Fs)          # the STL too is written while it is judged
                draw(Vs, Fs)

            try:
                result = textured_solid(shell, tiles, seed=args.seed, progress=bar,
                                        on_stored=judged)
                rep, s = result.report, result.stats
                if not pictures:
                    draw(result.vertices, result.faces)
                # the 3MF (formatted, written, read back, compared) here; the
                # STL was staged during the check and is renamed if it matches
                export_printable(out / f"{name}.3mf", result.vertices, result.faces,
                                 name=name, report=rep)
                export_printable(out / f"{name}.stl", result.vertices, result.faces,
                                 name=name, report=rep, staged=staged)
                pictures[-1][0].result()
                os.replace(pictures[-1][1], picture_path)
            except NotPrintableError as exc:
                print(f"geotex: error: {exc}", file=sys.stderr)
                return EXIT_NOT_PRINTABLE
            finally:
                for future, hidden in pictures:
                    if not future.cancel():
                        try:
                            future.result()
                        except Exception:       # its error, if any, was raised above
                            pass
                    hidden.unlink(missing_ok=True)
    files = [f"{name}.stl", f"{name}.3mf", f"{name}.png"]
    elapsed = time.perf_counter() - start
    summary = {"base": DEMO_BASE, "tiles": tiles.name, "size_mm": args.size_mm,
               "tile_mm": tile_mm, "seconds": round(elapsed, 2), "files": files,
               "shell": {"quads": shell.n_quads, "max_height_mm": shell.max_height,
                         "distortion": shell.distortion,
                         "coverage": shell.polycube.diagnostics.coverage},
               "map": s.to_dict(), "check": rep.to_dict()}
    with atomic_output(out / "report.json", "w") as fh:
        json.dump(summary, fh, indent=2, sort_keys=True)
    files.append("report.json")
    d = shell.distortion
    print(f"{DEMO_BASE}: {base.n_faces} faces scaled to {args.size_mm:g} mm; polycube of "
          f"{shell.n_quads} tiles of {tile_mm:.3g} mm (distortion area {d['area_mean']:.2f}, "
          f"angle {d['angle_mean']:.2f})")
    print(f"{tiles.name}: {s.elements} elements, {s.height:.3g} mm high, united with "
          f"the body: {s.faces} faces, printable: {'yes' if rep.printable else 'no'} "
          f"({elapsed:.1f} s)")
    print(f"results in {out}/:")
    for f in files:
        print(f"  {out / f}")
    return EXIT_OK if rep.printable else EXIT_NOT_PRINTABLE
