"""Would splitting elements make the union faster? The union stage, measured.

The union stage of the main job (``geotex/mapping/union.py``) unites every
mapped element with the base in one manifold3d batch boolean. Issue #13 asks
for <= 1 s at ~300k output faces, and the suggestion was that the boolean
should see fewer triangles: cut every element at a height ``w = level`` in
tile space (once per tile, so cut vertices on tile sides stay bit-identical
across tiles), send only the bottoms with a planar lid over each cut through
the boolean, and glue the tops back on.

This script measures, on the same base and mapped elements, in one process
(CPU seconds, best of ``--repeats``; the machine is shared, so wall times are
printed too but CPU is the figure to compare):

* the steps of today's union stage: the exact contact test of all elements
  (``element_contacts``), building the manifold3d operand, the boolean, the
  needle clean-up, the body selection;
* the boolean of the base with: the whole elements (today), the whole
  elements refined along the cut, the bottoms with their lids (what the split
  would send, at two cut heights), and the whole elements moved 1000 mm away
  (the same triangles with no intersection: the boolean's cost that does not
  depend on where the elements meet the base).

The cut itself (:func:`cut_tiles`, lids triangulated by manifold3d per tile,
cross-sections closed along tile sides) is the experiment's code and lives
here, not in the library, because the measurement says not to use it (see
``benchmarks/results/union_split.md``).

Usage: ``python benchmarks/bench_union_split.py [--data ../shared/data] [--quick]``
writes ``benchmarks/results/union_split.md``.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path
from typing import NamedTuple

import manifold3d
import numpy as np

from geotex.errors import InputError
from geotex.tiles.clip import refined_by_plane
from geotex.tiles.tileset import TileSet

HERE = Path(__file__).resolve().parent

#: Values of :attr:`TileCut.part`.
BOTTOM, TOP, LID = 0, 1, 2

#: Smallest distance, in tile units, between the cut and a tile vertex's ``w``.
CLEARANCE = 1e-6


class TileCut(NamedTuple):
    """A tile set cut at one height (:func:`cut_tiles`).

    Attributes
    ----------
    tiles : TileSet
        The tiles refined along the cut, with the lids as extra faces (cut
        vertices are float64: not every one is a float32 value).
    part : numpy.ndarray, (M,) int8
        :data:`BOTTOM`, :data:`TOP` or :data:`LID` for every face of ``tiles``.
    level : float
        Height of the cut (tile units; a float32 value).
    lidless : int
        Cross-sections left without a lid.
    """

    tiles: TileSet
    part: np.ndarray
    level: float
    lidless: int


def cut_level(tiles: TileSet, at: float) -> float:
    """The float32 height nearest above ``at`` that no tile vertex comes within
    :data:`CLEARANCE` of (so the cut never passes through a vertex).

    Raises
    ------
    InputError
        ``at`` not inside ``(-depth, height)``.
    """
    at = float(at)
    if not (-tiles.depth < at < tiles.height):
        raise InputError(f"cut height {at!r} must lie between -depth ({-tiles.depth:g}) and "
                         f"the tile height ({tiles.height:g})")
    w = np.unique(tiles.vertices[:, 2])
    level = float(np.float32(at))
    while True:
        near = np.abs(w - level) < CLEARANCE
        if not near.any():
            return level
        level = float(np.float32(w[near].max() + 2 * CLEARANCE))


def _perimeter(p: np.ndarray) -> np.ndarray:
    """Position along the tile's border, counter-clockwise from ``(0, 0)``: 0..4
    (NaN off the border or on a corner)."""
    u, v = p[:, 0], p[:, 1]
    s = np.full(len(p), np.nan)
    s = np.where(v == 0.0, u, s)
    s = np.where(u == 1.0, 1.0 + v, s)
    s = np.where(v == 1.0, 3.0 - u, s)
    s = np.where(u == 0.0, 4.0 - v, s)
    corner = ((u == 0.0) | (u == 1.0)) & ((v == 0.0) | (v == 1.0))
    s[corner] = np.nan
    return s


def _lid_loops(P: np.ndarray, cut: np.ndarray) -> tuple[list, int]:
    """Loops of vertex indices bounding the cross-sections of one tile.

    ``cut`` holds the directed lid edges. Chains that end on the tile border
    are closed along it, counter-clockwise, to the next chain's start; a
    closure that would turn a corner, or a chain that branches, leaves every
    chain it touches without a lid. Returns the loops and the number of
    cross-sections (chains) left out.
    """
    nxt = dict(zip(cut[:, 0].tolist(), cut[:, 1].tolist()))
    if len(nxt) != len(cut) or len(set(cut[:, 1].tolist())) != len(cut):
        return [], len(cut)                       # a branching cut: no lids in this tile
    heads = set(cut[:, 0].tolist()) - set(cut[:, 1].tolist())
    chains, seen = [], set()
    for a in sorted(heads):                       # open chains, border to border
        chain = [a]
        while chain[-1] in nxt:
            chain.append(nxt[chain[-1]])
        seen.update(chain)
        chains.append(chain)
    loops = []
    for a in sorted(set(nxt) - seen):             # closed loops inside the tile
        if a in seen:
            continue
        loop = [a]
        seen.add(a)
        while nxt[loop[-1]] != a:
            loop.append(nxt[loop[-1]])
            seen.add(loop[-1])
        loops.append(loop)
    if not chains:
        return loops, 0
    start = _perimeter(P[[c[0] for c in chains]])
    end = _perimeter(P[[c[-1] for c in chains]])
    bad = np.zeros(len(chains), dtype=bool)
    bad |= np.isnan(start) | np.isnan(end)
    follow = np.full(len(chains), -1)
    for i in np.flatnonzero(~bad):
        gap = np.mod(start - end[i], 4.0)
        gap[bad | np.isnan(gap)] = np.inf
        gap[gap == 0.0] = np.inf
        j = int(np.argmin(gap))
        # the closure runs along one side only: no corner between end and start
        if not np.isfinite(gap[j]) or np.floor(end[i]) != np.floor(end[i] + gap[j]) \
                or end[i] + gap[j] >= 4.0:
            bad[i] = True
            continue
        follow[i] = j
    # a chain is usable when following the closures from it comes back to it
    # through usable chains only
    left_out = 0
    done = np.zeros(len(chains), dtype=bool)
    for i in range(len(chains)):
        if done[i]:
            continue
        ring, j = [], i
        while j >= 0 and not done[j] and j not in ring:
            ring.append(j)
            j = follow[j]
        done[ring] = True
        if j == i and not bad[ring].any():
            loops.append([v for k in ring for v in chains[k]])
        else:
            left_out += len(ring)
    return loops, left_out


def _lids(P: np.ndarray, cut: np.ndarray) -> tuple[np.ndarray, int]:
    """Lid triangles of one tile (indices into ``P``) and cross-sections left out."""
    if len(cut) == 0:
        return np.zeros((0, 3), dtype=np.int64), 0
    loops, left_out = _lid_loops(P, cut)
    if not loops:
        return np.zeros((0, 3), dtype=np.int64), left_out
    idx = np.concatenate([np.asarray(lp, dtype=np.int64) for lp in loops])
    tri = np.asarray(manifold3d.triangulate([np.ascontiguousarray(P[lp, :2]) for lp in loops]),
                     dtype=np.int64).reshape(-1, 3)
    T = idx[tri]
    # the lids must close the loops exactly: every loop edge once, as given,
    # and every other edge twice in opposite directions
    want = np.concatenate([np.stack([lp, np.roll(lp, -1)], axis=1) for lp in
                           (np.asarray(lp) for lp in loops)])
    he = np.stack([T.ravel(), T[:, [1, 2, 0]].ravel()], axis=1)
    key = lambda e: e[:, 0] * (P.shape[0] + 1) + e[:, 1]      # noqa: E731
    k_he, k_rev, k_want = key(he), key(he[:, ::-1]), key(want)
    inner = ~np.isin(k_he, k_want)
    if (np.unique(k_he).size != k_he.size or not np.isin(k_want, k_he).all()
            or np.isin(key(want[:, ::-1]), k_he).any()
            or not np.isin(k_rev[inner], k_he[inner]).all()):
        return np.zeros((0, 3), dtype=np.int64), left_out + len(loops)
    return T, left_out


def cut_tiles(tiles: TileSet, level: float) -> TileCut:
    """Cut every tile at ``w = level`` and add lids over the cross-sections.

    Parameters
    ----------
    tiles : TileSet
    level : float
        Height of the cut, tile units (:func:`cut_level` picks one that
        passes through no vertex).

    Returns
    -------
    TileCut
        Same inputs, same bytes (no randomness; one tile at a time).

    Raises
    ------
    InputError
        ``level`` within :data:`CLEARANCE` of a tile vertex's ``w``, or outside
        ``(-depth, height)``.
    """
    level = float(level)
    if cut_level(tiles, level) != level:
        raise InputError(f"cut height {level!r} is not a float32 value clear of the tile "
                         "vertices; choose it with cut_level()")
    Vs, Fs, parts, lidless = [], [], [], 0
    for i in range(len(tiles)):
        V, F = tiles.tile(i)
        c = refined_by_plane(V, F, axis=2, value=level, snap=0.0, ordered=True)
        lids, out = _lids(c.vertices, c.cut)
        lidless += out
        Vs.append(c.vertices)
        Fs.append(np.vstack([c.faces, lids]))
        parts.append(np.concatenate([np.where(c.above, TOP, BOTTOM),
                                     np.full(len(lids), LID)]).astype(np.int8))
    nv = np.array([len(V) for V in Vs], dtype=np.int64)
    nf = np.array([len(F) for F in Fs], dtype=np.int64)
    out = TileSet(np.vstack(Vs), np.vstack(Fs), np.concatenate([[0], np.cumsum(nv)]),
                  np.concatenate([[0], np.cumsum(nf)]), tiles.groups, tiles.colors,
                  tiles.n_colors, tiles.height, tiles.depth, name=tiles.name,
                  metadata=dict(tiles.metadata, cut_level=level))
    return TileCut(out, np.concatenate(parts), level, lidless)


def _shell(data: Path, base: str, tile_size, work: Path):
    """The bench's shell: ``base`` decimated to 15k faces, scaled to 80 mm."""
    sys.path.insert(0, str(HERE))
    from bench_main_job import decimated_base

    from geotex.io import read_mesh
    from geotex.shells import build_shell

    src = {"spot": data / "base" / "spot_odedstein.obj",
           "bob": data / "base" / "bob_uv" / "bob_tri.obj"}[base]
    mesh = read_mesh(decimated_base(src, 15000, work / f"{base}_15k.obj"))
    V = mesh.vertices * (80.0 / float(np.ptp(mesh.vertices, axis=0).max()))
    return build_shell(V, mesh.faces, tile_size=tile_size)


def _best(fn, repeats: int):
    """(result, best CPU s, wall s of that run) of ``fn()``."""
    best = None
    for _ in range(repeats):
        c, t = time.process_time(), time.perf_counter()
        out = fn()
        dc, dt = time.process_time() - c, time.perf_counter() - t
        if best is None or dc < best[1]:
            best = (out, dc, dt)
    return best


def measure(shell, tileset: str, repeats: int) -> dict:
    """Steps of the union stage and the boolean variants on one shell."""
    from geotex.mapping import edge_colors, mapped_tiles, texture_height, tiles_for_quads
    from geotex.mapping.texture import ANCHOR
    from geotex.mapping.union import element_contacts, element_groups, united_with_base
    from geotex.mesh.needles import SLIVER_TOLERANCE, needle_free
    from geotex.mesh.solid import arrays_of_manifold, manifold_of
    from geotex.mesh.topology import compacted, face_components
    from geotex.tiles.catalog import load_named

    tiles = load_named(tileset)
    pc = shell.polycube
    lay = pc.layout
    tq = tiles_for_quads(tiles, lay.quad_axes, lay.quad_edge,
                         edge_colors(lay.edge_axis, tiles.n_colors, seed=0), bare=pc.quad_folded)
    scale = texture_height(shell, tiles) / tiles.height
    anchor = ANCHOR * shell.tile_size
    m = mapped_tiles(shell, tiles, tq, scale=scale, anchor=anchor)
    X, G = m.vertices, m.faces
    base = manifold_of(shell.base_vertices, shell.base_faces)
    row = {"quads": int(lay.n_quads), "mapped_faces": int(len(G))}

    def union(op):
        s = manifold3d.Manifold.batch_boolean([base, op], manifold3d.OpType.Add)
        s.num_tri()
        return s

    # today's steps, one at a time
    c, row["contacts"], row["contacts_wall"] = _best(lambda: element_contacts(X, G), repeats)
    label, group = element_groups(X, G, touching=c.touching, label=c.label)
    group[c.folded] = -1
    ops, row["build"], _ = _best(lambda: [manifold_of(*compacted(X, G[group[label] == g]))
                                          for g in range(int(group.max()) + 1)], repeats)
    def batch():
        s = manifold3d.Manifold.batch_boolean([base] + ops, manifold3d.OpType.Add)
        s.num_tri()                          # evaluate here (manifold3d is lazy)
        return s

    solid, row["boolean"], row["boolean_wall"] = _best(batch, repeats)
    V2, F2 = arrays_of_manifold(solid)
    diag = float(np.linalg.norm(np.ptp(np.vstack([shell.base_vertices, X]), axis=0)))
    (V3, F3, _), row["needles"], _ = _best(
        lambda: needle_free(V2, F2, tolerance=SLIVER_TOLERANCE * diag), repeats)
    _, row["components"], _ = _best(lambda: face_components(F3, V3.shape[0]), repeats)
    row["output_faces"] = int(len(F3))
    row["groups"] = int(group.max()) + 1
    row["elements"] = int((group >= 0).sum())
    # the library's union as it is now (build, small union of the elements that
    # meet, one boolean, needles, body), same contacts
    _, row["united"], _ = _best(lambda: united_with_base(shell.base_vertices, shell.base_faces,
                                                         X, G, contacts=c), repeats)

    # the boolean with one operand of: whole elements, refined, bottoms + lids, far away
    variants = {"whole": (X, G), "whole, moved 1000 mm away": (X + 1000.0, G)}
    for frac in (0.15, 0.5):
        level = cut_level(tiles, frac * tiles.height)
        cut = cut_tiles(tiles, level)
        mc = mapped_tiles(shell, cut.tiles, tq, scale=scale, anchor=anchor)
        part = cut.part[mc.tile_faces]
        tag = f"cut at {frac:g} of the height ({level * scale:.2f} mm)"
        variants[f"whole, refined along the {tag}"] = (mc.vertices, mc.faces[part != LID])
        variants[f"bottoms + lids, {tag}"] = (mc.vertices, mc.faces[part != TOP])
        row.setdefault("lidless", {})[tag] = cut.lidless
    row["variants"] = {}
    for name, (Xv, Gv) in variants.items():
        Xc, Gc = compacted(Xv, Gv)
        op, build, _ = _best(lambda: manifold_of(Xc, Gc), repeats)
        if op.status() != manifold3d.Error.NoError:
            row["variants"][name] = {"faces": int(len(Gc)), "status": op.status().name}
            continue
        out, boolean, wall = _best(lambda: union(op), repeats)
        row["variants"][name] = {"faces": int(len(Gc)), "build": build, "boolean": boolean,
                                 "boolean_wall": wall, "output_faces": int(out.num_tri())}
    return row


def main(argv=None) -> int:
    import tempfile

    ap = argparse.ArgumentParser()
    ap.add_argument("--data", default=str(HERE.parent.parent / "shared" / "data"))
    ap.add_argument("--quick", action="store_true", help="Spot at the automatic tile size only")
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--out", default=str(HERE / "results" / "union_split.md"))
    args = ap.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="geotex-bench-union-"))
    load0 = os.getloadavg()[0]
    cases = [("spot", None, "studs"), ("spot", 3.7, "studs"), ("spot", None, "chainmail")]
    if args.quick:
        cases = cases[:1]
    shells, rows = {}, []
    for base, ts, tset in cases:
        if (base, ts) not in shells:
            shells[base, ts] = _shell(Path(args.data), base, ts, work)
        row = measure(shells[base, ts], tset, args.repeats)
        row.update(base=base, tile=shells[base, ts].tile_size, tiles=tset,
                   load=os.getloadavg()[0])
        rows.append(row)
        print({k: v for k, v in row.items() if k != "variants"}, flush=True)
        for k, v in row["variants"].items():
            print("   ", k, v, flush=True)
    lines = [
        "# The union stage: where the time goes, and what splitting elements would save",
        "",
        f"Run {time.strftime('%Y-%m-%d %H:%M')} on {platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, manifold3d "
        f"{__import__('importlib.metadata').metadata.version('manifold3d')}; "
        "`python benchmarks/bench_union_split.py`. CPU seconds of this process (manifold3d's "
        f"threads included), best of {args.repeats}; 1-minute load {load0:.1f} at the start: "
        "the machine is shared, so wall times run up to ~2x the CPU times and only CPU "
        "times compare. Spot decimated to 15k faces at 80 mm (the main-job bench's base), "
        "seed 0.",
        "",
        "## Steps of the union stage (CPU s)",
        "",
        "Up to the sum: the union as it was before commit 0393d0e (one operand per colour "
        "group of the elements, all in one batch boolean with the base), step by step. Last "
        "column: `united_with_base` as it is now (the elements that meet nothing and the small "
        "union of those that meet concatenated into one operand, one boolean with the base, "
        "needles, body), with the same contact test result.",
        "",
        "| base | tile set | tile mm | elements | groups | output faces | contact test | "
        "build operands | boolean | needles | body | sum | now: contact test + "
        "united_with_base |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        steps = [r[k] for k in ("contacts", "build", "boolean", "needles", "components")]
        lines.append(f"| {r['base']} | {r['tiles']} | {r['tile']:.3g} | {r['elements']} | "
                     f"{r['groups']} | {r['output_faces']:,} | "
                     + " | ".join(f"{s:.2f}" for s in steps) + f" | **{sum(steps):.2f}** | "
                     f"**{r['contacts'] + r['united']:.2f}** |")
    lines += ["", "## The boolean of the base with one operand (CPU s)", "",
              "| base | tile set | tile mm | operand | operand faces | build | boolean | "
              "output faces |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        for name, v in r["variants"].items():
            if "boolean" not in v:
                lines.append(f"| {r['base']} | {r['tiles']} | {r['tile']:.3g} | {name} | "
                             f"{v['faces']:,} | {v['status']} | | |")
                continue
            lines.append(f"| {r['base']} | {r['tiles']} | {r['tile']:.3g} | {name} | "
                         f"{v['faces']:,} | {v['build']:.2f} | **{v['boolean']:.2f}** | "
                         f"{v['output_faces']:,} |")
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
