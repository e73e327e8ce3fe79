"""Benchmark: one ``hpm_texture`` run per process, for main / branch pairs under load.

Maps one image of ``../shared/data/images`` onto Spot simplified to 10k faces
(scale and seed as ``bench_hpm.py --all-images``) with whatever ``geotex`` is
on ``PYTHONPATH`` and prints one JSON line: CPU and wall seconds, the
1-minute load before and after, the uv md5 (as in ``results/hpm_images.md``),
placements and unfolded faces.  Two checkouts are compared by alternating
them, image by image, in the same shell loop, so that both meet the same
load (the 2 cores are shared with other jobs); see ``results/hpm_images.md``.

Run:  PYTHONPATH=CHECKOUT python benchmarks/bench_hpm_pair.py IMAGE [IMAGE ...]
"""

from __future__ import annotations

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


def main():
    V, F = bench_hpm.spot(10000)
    scale = 0.3 * float(np.linalg.norm(np.ptp(V, axis=0)))
    for name in sys.argv[1:]:
        img = bench_hpm.image(name)
        l0 = os.getloadavg()[0]
        c0, w0 = time.process_time(), time.perf_counter()
        r = hpm_texture(V, F, img, scale=scale, seed=0)
        c, w = time.process_time() - c0, time.perf_counter() - w0
        rep = r.report()
        print(json.dumps({
            "code": str(Path(geotex.__file__).resolve().parents[1]), "image": name,
            "cpu": round(c, 2), "wall": round(w, 2), "load_before": round(l0, 1),
            "load_after": round(os.getloadavg()[0], 1),
            "md5": hashlib.md5(r.uv.tobytes() + r.uv_faces.tobytes()).hexdigest()[:10],
            "placed": sum(lv["placed"] for lv in rep["levels"]),
            "unfolded": rep["levels"][-1]["filled_faces"]}), flush=True)


if __name__ == "__main__":
    main()
