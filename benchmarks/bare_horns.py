"""Issue #14, bare horns: out-of-reach area, elements left out and studs' spread, A/B.

Shells: the catalog's spot, blub, bob and torus rebuilt from their recipes
(same tile size) and the main job's Spot, Kitten and Bob 15k shells (what
``geotex texture X_15k.obj --size-mm 80`` builds, as bench_shell_shape.py).
Run it once with each checkout on PYTHONPATH to compare two versions of the
shell builder.

    python benchmarks/bare_horns.py build DIR [NAME ...]
        builds every shell into DIR/NAME.npz; one JSON line each: CPU seconds
        of the build (process_time), quads, safe height in tiles, the share of
        the base more than 1/4 and 1/8 tile outside the fitted surface, the
        fit's angle distortion;
    python benchmarks/bare_horns.py map DIR [NAME ...] [--sets SET ...]
        for every shell of DIR and every set, ``geotex map --shell DIR/NAME.npz``
        in its own process and ``geotex check`` on the written STL; one JSON
        line each (elements, left out folded / floating / at defects, retries,
        verdict); for studs also the footprint CV over the planar tiling's,
        before re-seating and as printed (bench_shell_shape.run_shell).

The tables are hand-written in results/bare.md.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import bench_shell_shape as bss  # noqa: E402
from corpus import geotex_check, geotex_cmd, run_measured  # noqa: E402

from geotex.param.polycube import bare_fraction  # noqa: E402
from geotex.shells import load_shell, save_shell  # noqa: E402
from geotex.shells.catalog import rebuild  # noqa: E402

CATALOG = ("spot", "blub", "bob", "torus")
SETS = ("studs", "chainmail", "scales", "weave", "knurl")
DATA = HERE.parents[1] / "shared" / "data"


def _shell(name: str, work: Path):
    if name in CATALOG:
        return rebuild(name)
    rel = dict((n.split()[0] + "15k", r) for n, r in bss.MAIN_JOB)[name]
    return bss.main_job_shell(Path(os.environ.get("GEOTEX_DATA", DATA)) / "base" / rel, work)


def build(out: Path, names) -> None:
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            t = time.process_time()
            shell = _shell(name, Path(tmp))
            cpu = time.process_time() - t
            save_shell(out / f"{name}.npz", shell)
            pc = shell.polycube
            args = (shell.base_vertices, shell.base_faces, pc.Y, pc.F)
            print(json.dumps({
                "shell": name, "cpu": round(cpu, 2), "load1": round(os.getloadavg()[0], 1),
                "tile": round(pc.tile_size, 4), "quads": pc.layout.n_quads,
                "bare_quads": int(pc.quad_folded.sum()),
                "height_tiles": round(shell.max_height / pc.tile_size, 3),
                "bare": round(bare_fraction(*args, depth=0.25 * pc.tile_size), 5),
                "bare_eighth": round(bare_fraction(*args, depth=0.125 * pc.tile_size), 5),
                "angle_mean": round(pc.diagnostics.distortion["angle_mean"], 3),
                "angle_p95": round(pc.diagnostics.distortion["angle_p95"], 3),
                "fitted": pc.diagnostics.voxels["fitted"]}), flush=True)


def map_sets(shells: Path, names, sets) -> None:
    env = dict(os.environ)
    tiles = bss.load_tiles(bss.SET)
    planar = bss.planar_figures(tiles)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for name in names:
            path = shells / f"{name}.npz"
            for tset in sets:
                out, rep = work / f"{name}-{tset}.stl", work / f"{name}-{tset}.json"
                run = run_measured([*geotex_cmd(), "map", "--tiles", tset, "--shell", str(path),
                                    "-o", str(out), "--report", str(rep)],
                                   timeout=900.0, log=work / "log", env=env)
                row = {"shell": name, "tiles": tset, "exit": run["exit"],
                       "wall": run["seconds"]}
                if run["exit"] == 0 and out.exists():
                    s = json.loads(rep.read_text())["stats"]
                    row.update(elements=s["elements"], folded=s["elements_folded"],
                               floating=s["elements_floating"],
                               at_defects=s.get("elements_left_out_at_defects"),
                               retries=s["union_retries"], faces=s["faces"])
                    row["check"] = geotex_check(out, env)[0]
                    out.unlink()
                if tset == bss.SET:
                    r = bss.run_shell(name, tiles, shaped=True, shell=load_shell(path))
                    row.update(cv_ratio=round(r["cv"] / planar["cv"], 2),
                               printed_cv_ratio=round(r["printed_cv"] / planar["cv"], 2),
                               left_out=r["left_out"], reseated=r["reseated"])
                print(json.dumps(row), flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("build", "map"))
    ap.add_argument("dir", type=Path)
    ap.add_argument("names", nargs="*")
    ap.add_argument("--sets", nargs="*", default=list(SETS))
    args = ap.parse_args()
    names = args.names or [*CATALOG, "spot15k", "kitten15k", "bob15k"]
    if args.what == "build":
        build(args.dir, names)
    else:
        map_sets(args.dir, names, args.sets)


if __name__ == "__main__":
    main()
