"""Benchmark: one ``hpm_texture`` run per process, for main / branch pairs under load.

Maps one image of ``../shared/data/images`` onto Spot simplified to 10k faces
(scale and seed as ``bench_hpm.py --all-images``) with whatever ``geotex`` is
on ``PYTHONPATH`` and prints one JSON line: CPU and wall seconds, the
1-minute load before and after, the uv md5 (as in ``results/hpm_images.md``),
placements and unfolded faces; with ``--quality`` also the quality columns of
``results/hpm_images.md`` (seam ratio border / within with the placed patches
as regions, where the map jumps, stretch mean / p95, rotation across borders
median / p75, orientation breaks), computed after the timed run.  Two
checkouts are compared by alternating them, image by image, in the same shell
loop, or by starting both at once (one per core), so that both meet the same
load (the 2 cores are shared with other jobs); see ``results/hpm_images.md``.

Run:  PYTHONPATH=CHECKOUT python benchmarks/bench_hpm_pair.py [--seed N] [--quality]
      IMAGE [IMAGE ...]
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import bench_hpm  # noqa: E402

import geotex  # noqa: E402
from geotex.image.hpm import hpm_texture  # noqa: E402
from geotex.image.seams import seam_contrast  # noqa: E402
from geotex.param.distortion import distortion_summary  # noqa: E402


def quality(V, F, img, r) -> dict:
    """The quality columns of ``results/hpm_images.md`` for one result ``r``."""
    regions = np.where(r.patch >= 0, r.patch, -1 - np.arange(F.shape[0]))
    d = distortion_summary(V, F, r.uv * [img.shape[1], img.shape[0]], uv_faces=r.uv_faces)
    rot = bench_hpm.border_rotation(V, F, r.uv, r.uv_faces, r.patch)
    q50, q75 = np.quantile(rot, [0.5, 0.75]) if rot.size else (0.0, 0.0)
    jumps = bench_hpm.continuity_regions(V, F, r.uv_faces)
    return {"seam": round(seam_contrast(V, F, r.uv, r.uv_faces, img, regions).ratio, 3),
            "jump": round(seam_contrast(V, F, r.uv, r.uv_faces, img, jumps).ratio, 3),
            "stretch_mean": round(d.stretch.mean, 3), "stretch_p95": round(d.stretch.p95, 3),
            "rot_median": round(float(q50), 1), "rot_p75": round(float(q75), 1),
            "breaks": round(bench_hpm.orientation_breaks(V, F, r.uv, r.uv_faces), 3)}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("images", nargs="+")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--quality", action="store_true")
    args = ap.parse_args()
    V, F = bench_hpm.spot(10000)
    scale = 0.3 * float(np.linalg.norm(np.ptp(V, axis=0)))
    for name in args.images:
        img = bench_hpm.image(name)
        l0 = os.getloadavg()[0]
        c0, w0 = time.process_time(), time.perf_counter()
        r = hpm_texture(V, F, img, scale=scale, seed=args.seed)
        c, w = time.process_time() - c0, time.perf_counter() - w0
        rep = r.report()
        row = {"code": str(Path(geotex.__file__).resolve().parents[1]), "image": name,
               "seed": args.seed, "cpu": round(c, 2), "wall": round(w, 2),
               "load_before": round(l0, 1), "load_after": round(os.getloadavg()[0], 1),
               "md5": hashlib.md5(r.uv.tobytes() + r.uv_faces.tobytes()).hexdigest()[:10],
               "placed": sum(lv["placed"] for lv in rep["levels"]),
               "unfolded": rep["levels"][-1]["filled_faces"]}
        if args.quality:
            row.update(quality(V, F, img, r))
        print(json.dumps(row), flush=True)


if __name__ == "__main__":
    main()
