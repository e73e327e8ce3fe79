"""Base area out of the texture's reach, on the catalog shells and the corpus shells.

For each catalog shell (geotex/shells/catalog, as stored) and for the shell
`geotex texture` builds by default (tile size automatic, base scaled to
80 mm) on every closed base of benchmarks/corpus.py (BASES + GENERATED), print
one JSON line: tile size, quads, sub-grid faces, coverage within a tile and
the share of the base area more than a quarter tile (BARE_DEPTH) and an
eighth of a tile outside the fitted surface (geotex.param.polycube.bare_fraction),
the CPU seconds of building the shell and the 1-minute load.

    python benchmarks/bare.py [--save DIR] [--load DIR] [NAME ...]

--save DIR writes each built shell to DIR/NAME.npz; --load DIR measures the
shells found there instead of building them (to measure shells another
checkout built). The result tables are hand-written in results/bare.md.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import corpus  # noqa: E402

from geotex.io import read_mesh  # noqa: E402
from geotex.param.polycube import bare_fraction  # noqa: E402
from geotex.param.polycube_size import BARE_DEPTH  # noqa: E402
from geotex.shells import build_shell, list_shells, load_named, load_shell, save_shell  # noqa: E402


def measure(shell, **extra) -> dict:
    pc = shell.polycube
    args = (shell.base_vertices, shell.base_faces, pc.Y, pc.F)
    return {"base": shell.name, "tile": round(pc.tile_size, 4), "quads": pc.layout.n_quads,
            "faces": int(pc.F.shape[0]),
            "within_tile": round(pc.diagnostics.coverage.get("within_tile", float("nan")), 4),
            "bare": round(bare_fraction(*args, depth=BARE_DEPTH * pc.tile_size), 4),
            "bare_eighth": round(bare_fraction(*args, depth=0.125 * pc.tile_size), 4),
            "attempts": len(pc.diagnostics.tile_search.get("attempts", [])), **extra}


def corpus_mesh(name: str):
    if name in corpus.GENERATED:
        V, F = corpus.generated_shape(name)
    else:
        m = read_mesh(corpus.DATA / name)
        V, F = m.vertices, m.faces
    return V * (corpus.SIZE_MM / float(np.ptp(V, axis=0).max())), F


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*")
    ap.add_argument("--save", type=Path)
    ap.add_argument("--load", type=Path)
    args = ap.parse_args()
    if not args.names:
        for r in list_shells():
            print(json.dumps(measure(load_named(r["name"]), kind="catalog")), flush=True)
    for name in args.names or corpus.BASES + corpus.GENERATED:
        stem = name if name in corpus.GENERATED else Path(name).stem
        if args.load is not None:
            print(json.dumps(measure(load_shell(args.load / f"{stem}.npz"), kind="corpus")),
                  flush=True)
            continue
        V, F = corpus_mesh(name)
        t0 = os.times()
        try:
            shell = build_shell(V, F, name=stem)
        except Exception as exc:                                # noqa: BLE001
            print(json.dumps({"base": stem, "error": str(exc)[:200]}), flush=True)
            continue
        t1 = os.times()
        cpu = t1.user - t0.user + t1.system - t0.system
        if args.save is not None:
            args.save.mkdir(parents=True, exist_ok=True)
            save_shell(args.save / f"{stem}.npz", shell)
        print(json.dumps(measure(shell, kind="corpus", cpu=round(cpu, 1),
                                 load1=round(os.getloadavg()[0], 1))), flush=True)


if __name__ == "__main__":
    main()
