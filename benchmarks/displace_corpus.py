"""Robustness sweep: ``geotex displace`` over every mesh file of ``shared/data``.

Every file of ``base/`` and ``broken/`` (recursively, mesh formats only) is
displaced with ``--image dots --depth 0.5 --size-mm 60 --faces 60000``, and
every image of ``images/`` and ``texture_exemplars/heightmaps/`` (PNG/JPEG,
recursively) is laid on Spot (``base/spot_odedstein.obj``) with the same
options; a written file is judged again by ``geotex check`` (read back from
disk).  Writes ``benchmarks/results/displace_corpus.md``.

Usage: ``python benchmarks/displace_corpus.py [--data ../shared/data]``
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

GEOTEX = [sys.executable, "-m", "geotex"]
MESH_SUFFIXES = {".stl", ".obj", ".ply", ".off", ".3mf", ".glb"}
IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg"}
IMAGE_BASE = Path("base") / "spot_odedstein.obj"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    here = Path(__file__).resolve().parent
    ap.add_argument("--data", type=Path, default=here.parent.parent / "shared" / "data")
    ap.add_argument("--out", type=Path, default=here / "results" / "displace_corpus.md")
    args = ap.parse_args(argv)
    files = sorted(p for sub in ("base", "broken") for p in (args.data / sub).rglob("*")
                   if p.suffix.lower() in MESH_SUFFIXES)
    images = sorted(p for sub in ("images", "texture_exemplars/heightmaps")
                    for p in (args.data / sub).rglob("*") if p.suffix.lower() in IMAGE_SUFFIXES)
    jobs = [(path, "dots") for path in files]
    jobs += [(args.data / IMAGE_BASE, img) for img in images]
    rows = []
    with tempfile.TemporaryDirectory(prefix="geotex-displace-corpus-") as tmp:
        for k, (path, image) in enumerate(jobs):
            out = Path(tmp) / f"{k}_{path.stem}.stl"
            t = time.perf_counter()
            res = subprocess.run(GEOTEX + ["displace", str(path), "--image", str(image),
                                           "--depth", "0.5", "--size-mm", "60", "--faces",
                                           "60000", "-o", str(out)],
                                 capture_output=True, text=True)
            dt = time.perf_counter() - t
            lines = [ln for ln in res.stderr.splitlines() if ln.strip()]
            if out.exists():
                chk = subprocess.run(GEOTEX + ["check", str(out)], capture_output=True, text=True)
                verdict = "written; `geotex check` on the file: " + (
                    "printable" if chk.returncode == 0 else "NOT printable")
            else:
                verdict = "not written: " + (lines[-1].replace(str(path), path.name)
                                             if lines else "(no message)")
            traceback = "Traceback" in res.stderr
            name = str(path.relative_to(args.data))
            if image != "dots":
                name = f"{Path(image).relative_to(args.data)} on {name}"
            rows.append((name, res.returncode, dt, len(lines), traceback, verdict))
            print(f"{rows[-1][0]}: exit {res.returncode} {dt:.1f} s {verdict[:100]}", flush=True)
    load = os.getloadavg()
    text = ["# `geotex displace` over the shared corpus (robustness sweep)", "",
            f"{time.strftime('%Y-%m-%d')}, x86_64, {os.cpu_count()} cores, 1-minute load "
            f"{load[0]:.1f} at the end. `python benchmarks/displace_corpus.py`: every mesh file "
            "of `shared/data/base` and `shared/data/broken`, "
            "`geotex displace FILE --image dots --depth 0.5 --size-mm 60 --faces 60000 "
            "-o OUT.stl`, then every image of `shared/data/images` and "
            "`shared/data/texture_exemplars/heightmaps` on Spot (`--image IMAGE`, the same "
            "options; rows \"IMAGE on BASE\"); a written file is judged again by "
            "`geotex check` on the file. "
            "A part that is not a closed, manifold, consistently oriented solid free of "
            "self-intersections is refused before any relief is built (exit 2, one line).", "",
            "| file | exit | s | stderr lines | traceback | result |",
            "|---|---|---|---|---|---|"]
    for name, code, dt, n, tb, verdict in rows:
        text.append(f"| {name} | {code} | {dt:.1f} | {n} | {'yes' if tb else 'no'} | "
                    f"{verdict.replace('|', '/')} |")
    args.out.write_text("\n".join(text) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
