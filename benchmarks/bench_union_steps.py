"""The union stage step by step, and how much of the base lies near elements.

Spot and Bob decimated to 15k faces at 80 mm (the main-job bench's bases) with
studs, seed 0, at the automatic tile size (~370k output faces) and at 3.7 mm
(~1.2M). For each: CPU seconds (this process, manifold3d's threads included,
best of ``--repeats``) of the contact test, the operand build, the boolean,
the needle clean-up and the whole ``united_with_base``; the share of base faces
whose box meets some element's box (what a boolean on a cut-down base could
leave out).

Usage: ``python benchmarks/bench_union_steps.py [--data ../shared/data]``
writes ``benchmarks/results/union_steps.md``.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import manifold3d
import numpy as np

HERE = Path(__file__).resolve().parent


def _mapped(shell):
    from geotex.mapping import edge_colors, mapped_tiles, texture_height, tiles_for_quads
    from geotex.mapping.texture import ANCHOR
    from geotex.tiles.catalog import load_named

    tiles = load_named("studs")
    lay = shell.polycube.layout
    tq = tiles_for_quads(tiles, lay.quad_axes, lay.quad_edge,
                         edge_colors(lay.edge_axis, tiles.n_colors, seed=0),
                         bare=shell.polycube.quad_folded)
    scale = texture_height(shell, tiles) / tiles.height
    return mapped_tiles(shell, tiles, tq, scale=scale, anchor=ANCHOR * shell.tile_size)


def _best(fn, repeats):
    best = None
    for _ in range(repeats):
        c = time.process_time()
        out = fn()
        dc = time.process_time() - c
        best = (out, dc) if best is None or dc < best[1] else best
    return best


def _near_base(V, F, X, G, label) -> float:
    """Share of base faces whose box meets some element's box."""
    from scipy.spatial import cKDTree

    n = int(label.max()) + 1
    P = X[G]
    lo = np.full((n, 3), np.inf)
    hi = np.full((n, 3), -np.inf)
    np.minimum.at(lo, label, P.min(axis=1))
    np.maximum.at(hi, label, P.max(axis=1))
    B = V[F]
    blo, bhi = B.min(axis=1), B.max(axis=1)
    r = np.linalg.norm(0.5 * (hi - lo), axis=1).max() + np.linalg.norm(
        0.5 * (bhi - blo), axis=1).max()
    near = np.zeros(len(F), dtype=bool)
    for i, js in enumerate(cKDTree(0.5 * (lo + hi)).query_ball_point(0.5 * (blo + bhi), r)):
        js = np.asarray(js, dtype=np.int64)
        near[i] = bool(js.size) and bool(np.any(np.all((lo[js] <= bhi[i]) & (hi[js] >= blo[i]),
                                                       axis=1)))
    return float(near.mean())


def measure(shell, repeats: int) -> dict:
    from geotex.mapping.union import element_contacts, element_pairs, united_with_base
    from geotex.mesh.needles import SLIVER_TOLERANCE, needle_free
    from geotex.mesh.solid import arrays_of_manifold, manifold_of
    from geotex.mesh.topology import compacted

    m = _mapped(shell)
    V, F, X, G = shell.base_vertices, shell.base_faces, m.vertices, m.faces
    label = m.element[G[:, 0]]
    contacts, t_contacts = _best(lambda: element_contacts(X, G, label=label), repeats)
    _, t_pairs = _best(lambda: element_pairs(X, G, touching=contacts.touching,
                                             label=contacts.label), repeats)
    keep = ~np.isin(contacts.label, contacts.folded)
    XX, GG = compacted(X, G[keep])
    _, t_build = _best(lambda: manifold_of(XX, GG).num_tri(), repeats)
    base, elements = manifold_of(V, F), manifold_of(XX, GG)
    _, t_bool = _best(lambda: manifold3d.Manifold.batch_boolean(
        [base, elements], manifold3d.OpType.Add).num_tri(), repeats)
    A = arrays_of_manifold(manifold3d.Manifold.batch_boolean([base, elements],
                                                              manifold3d.OpType.Add))
    tol = SLIVER_TOLERANCE * float(np.linalg.norm(np.ptp(np.vstack([V, X]), axis=0)))
    _, t_needles = _best(lambda: needle_free(*A, tolerance=tol), repeats)
    out, t_united = _best(lambda: united_with_base(V, F, X, G, contacts=contacts), repeats)
    return {"faces": len(out[1]), "elements": int(label.max()) + 1, "element_faces": len(G),
            "contacts": t_contacts, "pairs": t_pairs, "build": t_build, "boolean": t_bool,
            "needles": t_needles, "united": t_united,
            "near": _near_base(V, F, X, G, label), "base_faces": len(F)}


def main(argv=None) -> int:
    sys.path.insert(0, str(HERE))
    from bench_union_split import _shell

    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=str(HERE.parent.parent / "shared" / "data"))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--out", default=str(HERE / "results" / "union_steps.md"))
    args = ap.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="geotex-bench-union-steps-"))
    load0 = os.getloadavg()[0]
    rows = []
    for base in ("spot", "bob"):
        for ts in (None, 3.7):
            r = measure(_shell(Path(args.data), base, ts, work), args.repeats)
            r.update(base=base, tile=("auto" if ts is None else f"{ts}"))
            rows.append(r)
            print(r, flush=True)
    lines = [
        "# The union stage step by step (CPU s)", "",
        f"Run {time.strftime('%Y-%m-%d %H:%M')} on {platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, manifold3d; "
        "`python benchmarks/bench_union_steps.py`. CPU seconds of this process (manifold3d's "
        f"threads included), best of {args.repeats}; 1-minute load {load0:.1f} at the start and "
        f"{os.getloadavg()[0]:.1f} at the end (a shared machine: only CPU seconds compare). "
        "Bases decimated to 15k faces at 80 mm, studs, seed 0.", "",
        "Contact test: `element_contacts` with the map's labels. Build: the elements operand "
        "(folded ones left out) by `manifold_of`. Base near: base faces whose box meets an "
        "element's box.",
        "",
        "| base | tile mm | elements | element faces | output faces | contact test | pairs "
        "| build | boolean | needles | united_with_base | base near |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['base']} | {r['tile']} | {r['elements']} | {r['element_faces']:,} "
            f"| {r['faces']:,} | {r['contacts']:.3f} | {r['pairs']:.3f} "
            f"| {r['build']:.3f} | {r['boolean']:.3f} | {r['needles']:.3f} "
            f"| **{r['united']:.3f}** | {r['near']:.1%} of {r['base_faces']:,} |")
    Path(args.out).write_text("\n".join(lines) + "\n")
    print("wrote", args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
