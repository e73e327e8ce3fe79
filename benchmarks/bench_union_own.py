"""The own local union of the base with elements that cross only the base, against manifold3d.

Spot decimated to 15k faces at 80 mm (the main-job bench's base), seed 0: studs at
the automatic tile size (~370k output faces) and at 3.7 mm (~1.2M), chain mail at
the automatic size. For each, the operands ``united_with_base`` would give a
local union: the base united with the elements that meet another (a small
boolean) and the elements that meet nothing. Interleaved in one process,
``--repeats`` rounds: manifold3d's boolean of the two (operand build, boolean,
arrays out) and ``crossing_union`` of them with and without its exact test of
flat pieces (a boolean adds the elements it leaves out), CPU seconds of this
process (manifold3d's threads included) and wall seconds; every round's output
byte-identical to the first. Then the volume and face count of each, the
exact self-intersection test of each result, and ``geotex check``'s verdict on
its STL after the needle clean-up (written and read back).

Usage: ``python benchmarks/bench_union_own.py [--data ../shared/data]`` writes
``benchmarks/results/union_own.md`` (hand-written sections kept).
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


def _shell(data: Path, tile_size, work: Path):
    sys.path.insert(0, str(HERE))
    from bench_main_job import decimated_base

    from geotex.io import read_mesh
    from geotex.shells import build_shell

    mesh = read_mesh(decimated_base(data / "base" / "spot_odedstein.obj", 15000,
                                    work / "spot_15k.obj"))
    V = mesh.vertices * (80.0 / float(np.ptp(mesh.vertices, axis=0).max()))
    return build_shell(V, mesh.faces, tile_size=tile_size)


def _operands(shell, tileset):
    from geotex.mapping import edge_colors, mapped_tiles, texture_height, tiles_for_quads
    from geotex.mapping.texture import ANCHOR
    from geotex.mapping.union import element_contacts, element_pairs
    from geotex.mesh.solid import arrays_of_manifold, manifold_of
    from geotex.mesh.topology import compacted, greedy_colouring
    from geotex.tiles.catalog import load_named

    tiles = load_named(tileset)
    lay = shell.polycube.layout
    tq = tiles_for_quads(tiles, lay.quad_axes, lay.quad_edge,
                         edge_colors(lay.edge_axis, tiles.n_colors, seed=0),
                         bare=shell.polycube.quad_folded)
    m = mapped_tiles(shell, tiles, tq, scale=texture_height(shell, tiles) / tiles.height,
                     anchor=ANCHOR * shell.tile_size)
    V, F, X, G = shell.base_vertices, shell.base_faces, m.vertices, m.faces
    c = element_contacts(X, G, label=m.element[G[:, 0]])
    label, pairs = element_pairs(X, G, touching=c.touching, label=c.label)
    n_el = int(label.max()) + 1
    usable = np.ones(n_el, dtype=bool)
    usable[c.folded] = False
    pairs = pairs[usable[pairs].all(axis=1)]
    group = greedy_colouring(n_el, pairs)
    meets = np.zeros(n_el, dtype=bool)
    meets[pairs.ravel()] = True
    solid = manifold_of(V, F)
    if meets.any():
        solid = manifold3d.Manifold.batch_boolean(
            [solid] + [manifold_of(*compacted(X, G[((group == g) & meets)[label]]))
                       for g in range(int(group.max()) + 1)], manifold3d.OpType.Add)
    alone = (usable & ~meets)[label]
    XA, GA = compacted(X, G[alone])
    _, element = np.unique(label[alone], return_inverse=True)
    return (V, F, X, G, c), arrays_of_manifold(solid), (XA, GA, element), int(meets.sum())


def _checked(V, F, X, work, name):
    """Needles removed as ``united_with_base`` does, written as STL, read back, checked."""
    from geotex.check import check_mesh
    from geotex.io import read_mesh, write_mesh
    from geotex.mesh.needles import SLIVER_TOLERANCE, needle_free
    from geotex.mesh.record import Mesh

    diag = float(np.linalg.norm(np.ptp(np.vstack([V, X]), axis=0)))
    V2, F2, _ = needle_free(V, F, tolerance=SLIVER_TOLERANCE * diag)
    path = work / f"{name}.stl"
    write_mesh(path, Mesh(V2, F2))
    back = read_mesh(path)
    rep = check_mesh(back.vertices, back.faces)
    return len(F2), bool(rep.printable), int(rep.self_intersecting_pairs or 0)


def measure(shell, tileset, repeats, work):
    import geotex.mapping.crossing as crossing
    from geotex.check.intersections import self_intersecting_pairs
    from geotex.mesh.solid import arrays_of_manifold, manifold_of
    from geotex.mesh.topology import compacted

    (V, F, X, G, c), (Vb, Fb), (XA, GA, element), n_meets = _operands(shell, tileset)
    base = manifold_of(Vb, Fb)

    def own(guard):
        r = crossing.crossing_union(Vb, Fb, XA, GA, element=element, flat_test=guard)
        if r.left_out.size == 0:
            return r.vertices, r.faces, r.left_out
        # the elements left out, added by a boolean (as a caller would)
        rest = manifold_of(*compacted(XA, GA[np.isin(element, r.left_out)]))
        s = manifold3d.Manifold.batch_boolean([manifold_of(r.vertices, r.faces), rest],
                                              manifold3d.OpType.Add)
        return (*arrays_of_manifold(s), r.left_out)

    def boolean():
        s = manifold3d.Manifold.batch_boolean([base, manifold_of(XA, GA)], manifold3d.OpType.Add)
        return (*arrays_of_manifold(s), None)

    runs = {"guarded": lambda: own(True), "unguarded": lambda: own(False), "boolean": boolean}
    runs["guarded"]()                      # compiled code loaded
    times = {k: [] for k in runs}
    outs = {}
    names = list(runs)
    for r in range(repeats):
        for name in (names if r % 2 == 0 else names[::-1]):
            t, w = time.process_time(), time.perf_counter()
            out = runs[name]()
            times[name].append((time.process_time() - t, time.perf_counter() - w))
            if name in outs:
                assert out[0].tobytes() == outs[name][0].tobytes(), "not deterministic"
                assert out[1].tobytes() == outs[name][1].tobytes(), "not deterministic"
            outs[name] = out
    row = {"elements": int(element.max()) + 1, "meets": n_meets, "element_faces": len(GA)}
    for name, (V2, F2, left) in outs.items():
        tag = f"{tileset}_{shell.tile_size:.3g}_{name}"
        faces, printable, pairs = _checked(V2, F2, X, work, tag)
        row[name] = {"times": times[name], "faces": len(F2),
                     "volume": manifold_of(V2, F2).volume(),
                     "raw_pairs": len(self_intersecting_pairs(V2, F2)),
                     "left_out": -1 if left is None else int(left.size),
                     "stl_faces": faces, "printable": printable, "stl_pairs": pairs}
    return row


def main(argv=None) -> int:
    from handkept import write_keeping_hand_sections

    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=str(HERE.parent.parent / "shared" / "data"))
    ap.add_argument("--repeats", type=int, default=4)
    ap.add_argument("--out", default=str(HERE / "results" / "union_own.md"))
    args = ap.parse_args(argv)
    sys.path.insert(0, str(HERE))
    work = Path(tempfile.mkdtemp(prefix="geotex-bench-union-own-"))
    load0 = os.getloadavg()[0]
    rows = []
    shells = {}
    for ts, tileset in ((None, "studs"), (3.7, "studs"), (None, "chainmail")):
        if ts not in shells:
            shells[ts] = _shell(Path(args.data), ts, work)
        r = measure(shells[ts], tileset, args.repeats, work)
        r.update(tile=shells[ts].tile_size, tiles=tileset)
        rows.append(r)
        print(r, flush=True)

    def med(xs, k):
        return float(np.median([x[k] for x in xs]))

    lines = [
        "# The own local union against manifold3d's boolean", "",
        f"Run {time.strftime('%Y-%m-%d %H:%M')} on {platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, manifold3d "
        f"{__import__('importlib.metadata').metadata.version('manifold3d')}; "
        "`python benchmarks/bench_union_own.py`. Spot decimated to 15k faces at 80 mm, seed 0. "
        f"1-minute load {load0:.1f} at the start, {os.getloadavg()[0]:.1f} at the end. "
        f"Median of {args.repeats} interleaved rounds in one process; CPU seconds of the "
        "process (manifold3d's threads included), and wall seconds.", "",
        "Operands: the base united with the elements that meet another (as "
        "`united_with_base` does it, a small boolean) and the elements that meet nothing. "
        "Boolean: manifold3d's operand build and boolean of the two (and the arrays out). "
        "Own: `geotex.mapping.crossing.crossing_union` of the two, with its exact test of "
        "the flat pieces (`_FLAT`) or without it, and a boolean for the elements it leaves "
        "out. Crossing pairs: the exact self-intersection test of the result before the "
        "needle clean-up. STL: `needle_free` as `united_with_base` runs it, written as STL, "
        "read back, `geotex check`.", "",
        "| tile set | tile mm | elements alone | meeting | element faces | union "
        "| CPU s | wall s | left out | faces | volume / boolean's - 1 | crossing pairs before "
        "needles | STL faces | STL check |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        ref = r["boolean"]["volume"]
        for name in ("boolean", "guarded", "unguarded"):
            v = r[name]
            label = {"boolean": "manifold3d boolean", "guarded": "own, flat pieces tested",
                     "unguarded": "own, untested"}[name]
            lines.append(
                f"| {r['tiles']} | {r['tile']:.3g} | {r['elements']} | {r['meets']} "
                f"| {r['element_faces']:,} | {label} | **{med(v['times'], 0):.3f}** "
                f"| {med(v['times'], 1):.3f} | {'' if v['left_out'] < 0 else v['left_out']} "
                f"| {v['faces']:,} | {v['volume'] / ref - 1:.1e} | {v['raw_pairs']} "
                f"| {v['stl_faces']:,} | {'printable' if v['printable'] else 'NOT printable'}"
                f"{'' if v['printable'] else ' (' + str(v['stl_pairs']) + ' pairs)'} |")
    write_keeping_hand_sections(args.out, "\n".join(lines) + "\n")
    print("wrote", args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
