"""Benchmark: seams of merged elements (normal jump and gap where two elements were joined).

Every merge the quilting engine makes is recorded (``merge_elements`` wrapped
where :mod:`geotex.quilting.placement` calls it), on

1. single strand merges: two copies of a weave strand overlapping by one
   pitch (the cases of ``tests/test_quilting.py``), and two different studs
   fused (the general, non-corresponding path);
2. quilted weaves (the only procedural exemplar whose elements join in
   quilting): 2x2 -> 3x3 (seed 1, the test), 2x1.5 -> 4x3 (seed 0, the
   quilting benchmark) and 2x2 -> 4x4 (seed 0, examples/quilting.py);
3. catalog tile sets rebuilt from their recipes (``studs``, ``knurl``; with
   ``--all`` also ``scales-planar`` and ``studs-complete``), every merge of
   every tile's interior quilting, including merges the builder later undoes.

For stitched merges: normal jump (degrees) at every seam edge -- the angle
between the two faces on either side of an edge of the seam -- summarised as
the mean over all seam edges, the mean of each merge's largest, and the
largest; and the seam gap (largest distance between the two seam curves
that had to be bridged, relative to the mean edge length of the pair; 0
when they are welded).  Corresponding pairs (copies of one element, pieces
of one strand) and other fused pairs are reported apart.

Run:  python benchmarks/bench_seams.py [--all] [--label TEXT] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import time

import numpy as np

import geotex.quilting.placement as placement
from geotex.exemplars import exemplar
from geotex.mesh.geometry import mean_edge_length
from geotex.mesh.primitives import icosphere
from geotex.quilting import merge_elements, quilt_texture, split_elements

RECORD: list = []
_merge = placement.merge_elements


def _recording(VA, FA, VB, FB, **kw):
    r = _merge(VA, FA, VB, FB, **kw)
    _note(r, VA, FA, VB, FB)
    return r


def _note(r, VA, FA, VB, FB):
    h = 0.5 * (mean_edge_length(np.asarray(VA, float), np.asarray(FA), per_face=True)
               + mean_edge_length(np.asarray(VB, float), np.asarray(FB), per_face=True))
    RECORD.append({"status": r.status, "corresponding": bool(r.corresponding),
                   "gap": r.seam_gap / h, "jump_max": r.seam_normal_jump,
                   "jump_mean": r.seam_normal_jump_mean,
                   "edges": int(getattr(r, "seam_edges", 0))})


def stud(center, r=0.15, sub=3):
    V, F = icosphere(sub)
    V = V * [r, r, 0.2]
    V[:, 2] = np.where(V[:, 2] > 0, V[:, 2], np.maximum(V[:, 2], -0.05))
    return V + [center[0], center[1], 0.0], F


def strand(k):
    ex = exemplar("weave", size=(2.0, 2.0), seed=0)
    e = split_elements(ex.vertices, ex.faces, element_ids=ex.elements())[k]
    return e.V, e.F


def summary(rows):
    st = [r for r in rows if r["status"] == "stitched"]
    out = {"merges": len(rows), "stitched": len(st),
           "union": sum(r["status"] == "union" for r in rows)}
    for tag, sel in (("corresponding", [r for r in st if r["corresponding"]]),
                     ("other", [r for r in st if not r["corresponding"]])):
        if not sel:
            out[tag] = None
            continue
        mx = np.array([r["jump_max"] for r in sel])
        mn = np.array([r["jump_mean"] for r in sel])
        ed = np.array([max(r["edges"], 1) for r in sel])
        out[tag] = {"n": len(sel), "welded": sum(r["gap"] == 0 for r in sel),
                    "jump_edge_mean": float(np.nansum(mn * ed) / ed[np.isfinite(mn)].sum()),
                    "jump_merge_mean": float(np.nanmean(mn)),
                    "jump_maxima_mean": float(np.nanmean(mx)),
                    "jump_max": float(np.nanmax(mx)),
                    "gap_max": float(np.nanmax([r["gap"] for r in sel]))}
    return out


def picture(path):
    """Close-up of the join that main welded worst: strip fallback, crease seam, default weld.

    The quilt 2x1.5 -> 4x3 (seed 3) is made once with every merge's inputs
    recorded; the corresponding pair whose weld bends most with
    ``crease_cost=0`` is merged three ways: ``weld=False, crease_cost=0``
    (the pulled strip that main fell back to when this weld folded: the
    same cut, the same result), ``crease_cost=0`` (welded at points of equal
    arc-length parameter, but the cut lies on a ring where the strand
    creases) and the default.
    """
    from geotex.render import Panel, render_panels
    pairs = []

    def keep(VA, FA, VB, FB, **kw):
        r = _merge(VA, FA, VB, FB, **kw)
        if r.status == "stitched" and r.corresponding:
            pairs.append((VA, FA, VB, FB, kw))
        return r

    placement.merge_elements = keep
    ex = exemplar("weave", size=(2.0, 1.5), seed=0)
    quilt_texture(ex, out_size=(4.0, 3.0), seed=3, boundary="clip")
    placement.merge_elements = _merge
    worst = None
    for VA, FA, VB, FB, kw in pairs:
        r = merge_elements(VA, FA, VB, FB, **{**kw, "crease_cost": 0.0})
        if worst is None or r.seam_normal_jump_mean > worst[0]:
            worst = (r.seam_normal_jump_mean, (VA, FA, VB, FB, kw))
    VA, FA, VB, FB, kw = worst[1]
    # the seam lies in the overlap of the two elements' boxes
    centre = 0.5 * (np.maximum(VA.min(axis=0), VB.min(axis=0))
                    + np.minimum(VA.max(axis=0), VB.max(axis=0)))
    runs = [(merge_elements(VA, FA, VB, FB, **{**kw, **opts}), what) for opts, what in (
        ({"weld": False, "crease_cost": 0.0}, "strip (main: the weld folded)"),
        ({"crease_cost": 0.0}, "weld, cut on a crease (crease_cost=0)"),
        ({}, "weld (default)"))]
    render_panels([
        Panel(r.vertices, r.faces, show_edges=True, closeup=centre, closeup_radius=0.35,
              highlight={"bends of 12-60 degrees": _bent_edges(r.vertices, r.faces, 12, 60)},
              title=f"{what}: gap {r.seam_gap:.2g}, seam jump "
                    f"{r.seam_normal_jump_mean:.1f} mean / {r.seam_normal_jump:.1f} max")
        for r, what in runs], path, size=(700, 520), up="z")


def _bent_edges(V, F, lo, hi):
    """Edges (k, 2) whose two faces meet at an angle between ``lo`` and ``hi`` degrees."""
    from geotex.mesh.geometry import face_normals
    from geotex.mesh.topology import edge_topology
    topo = edge_topology(F, V.shape[0])
    inner = topo.face_count == 2
    ef = topo.edge_faces()[inner]
    N = face_normals(V, F)
    ang = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", N[ef[:, 0]], N[ef[:, 1]]),
                                       -1.0, 1.0)))
    return topo.edges[inner][(ang >= lo) & (ang <= hi)]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--all", action="store_true")
    ap.add_argument("--only", default="")
    ap.add_argument("--json")
    ap.add_argument("--picture", help="write a close-up of the join main welded worst (three ways) here")
    args = ap.parse_args()
    if args.picture:
        picture(args.picture)
        return
    placement.merge_elements = _recording
    results = {}

    def case(name, fn):
        if args.only and args.only not in name:
            return
        RECORD.clear()
        t0 = time.perf_counter()
        fn()
        results[name] = summary(list(RECORD))
        results[name]["seconds"] = round(time.perf_counter() - t0, 1)
        print(name, json.dumps(results[name]), flush=True)

    def strands():
        for k, shift in ((0, (1.0, 0.0)), (0, (-1.0, 0.0)), (4, (0.0, 1.0))):
            VB, FB = strand(k)
            VA = VB + [shift[0], shift[1], 0.0]
            r = merge_elements(VA, FB, VB, FB, corresponding_only=True)
            _note(r, VA, FB, VB, FB)

    def studs():
        VA, FA = stud((0, 0))
        for off in ((0.15, 0.05), (0.22, 0.1)):
            VB, FB = stud(off, r=0.14)
            r = merge_elements(VA, FA, VB, FB, align=False)
            _note(r, VA, FA, VB, FB)

    case("strand pairs (3)", strands)
    case("two studs fused (2)", studs)
    for (sx, sy), (ox, oy), seed in (((2.0, 2.0), (3.0, 3.0), 1), ((2.0, 1.5), (4.0, 3.0), 0),
                                     ((2.0, 2.0), (4.0, 4.0), 0)):
        ex = exemplar("weave", size=(sx, sy), seed=0)
        case(f"weave quilt {sx:g}x{sy:g} -> {ox:g}x{oy:g} seed {seed}",
             lambda: quilt_texture(ex, out_size=(ox, oy), seed=seed, boundary="clip"))
    from geotex.tiles.catalog import rebuild
    for name in ("studs", "knurl") + (("scales-planar", "studs-complete") if args.all else ()):
        case(f"tiles {name}", lambda: rebuild(name))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=1)


if __name__ == "__main__":
    main()
