"""
A spiky texture moved between shapes of different proportions (paper Figs. 1, 5, 6)
===================================================================================

A procedural "lychee" (a sphere with spikes, the texture extracted over its
smooth base) is edited with a whirl -- ``wrap`` along a swirl around the
vertical axis, so every spike curls around the pole -- and transferred
through the sphere map (``transfer_between_shapes``: both bases mapped
near-conformally onto the unit sphere, aligned by principal axes) onto an
"avocado" (a pear-shaped, longer base) and onto a bent two-lobed "bean".
A conformal map keeps angles, not areas: where a target bulges out less
than the source (the avocado's narrow end, the bean's waist) spikes come
closer together, where it bulges more they spread (on Spot, whose head, legs
and ears take small parts of the sphere, the contrast is extreme; see
benchmarks/results/heighttilt_transfer.md).
Heights are resampled and the tilt 1-form integrated along the target
edges, so the curled spikes keep their height and curl on both targets.

Top row: the lychee, the whirled lychee, the avocado and the bean.  Bottom row:
close-ups of the whirled lychee, the avocado and the bean.

``GEOTEX_EXAMPLES_QUICK=1`` (the test suite) moves it onto the avocado only.

Run:  python examples/heighttilt_shapes.py [OUT_DIR]     (default docs/gallery)
"""

from __future__ import annotations

import io
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from PIL import Image

from geotex.heighttilt import apply_texture, extract_texture, spiky_sphere, wrap
from geotex.heighttilt.transfer import transfer_between_shapes
from geotex.mesh.geometry import face_areas
from geotex.mesh.primitives import icosphere
from geotex.render import Panel, render_panels

COLOR = "#b5503c"
TARGET_COLOR = "#6f8f3a"
#: Direction the panels are seen from (geotex.render's three-quarter view with z up).
VIEW = np.array([0.75, -1.0, 0.55])


def scaled_to_area(V, F, area):
    return (V - V.mean(axis=0)) * np.sqrt(area / face_areas(V, F).sum())


def busy_point(V, F, height, direction, radius):
    """A vertex facing ``direction`` with the most spike tips within ``radius``."""
    from scipy.spatial import cKDTree

    from geotex.heighttilt import base_normals
    from geotex.mesh.topology import edge_topology

    E = edge_topology(F, len(V)).edges
    top = np.full(len(V), -np.inf)
    np.maximum.at(top, E[:, 0], height[E[:, 1]])
    np.maximum.at(top, E[:, 1], height[E[:, 0]])
    tips = (height > top) & (height > 0.5 * height.max())
    facing = base_normals(V, F) @ (direction / np.linalg.norm(direction)) > 0.7
    counts = np.array([len(x) for x in cKDTree(V[tips]).query_ball_point(V, radius)])
    counts[~facing] = -1
    return V[np.argmax(counts)]


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    V0, F, Vs = spiky_sphere(subdivisions=6, spikes=90, width=0.1, height=0.24,
                             lean_degrees=15.0, seed=3)
    tex, Vs = extract_texture(V0, F, base=Vs)
    swirl = np.cross([0.0, 0.0, 1.0], Vs)                       # around the vertical axis
    whirled = wrap(Vs, F, tex, k=4.0, direction=swirl)
    area = float(face_areas(Vs, F).sum())

    V, Fi = icosphere(6)
    r = 1.0 + 0.35 * V[:, 2]
    avocado = (scaled_to_area(V * r[:, None] * [1.0, 0.85, 1.6], Fi, 1.6 * area), Fi)
    z = V[:, 2]
    peanut = V * (1.0 - 0.2 * np.cos(np.pi * z))[:, None] * [1.0, 1.0, 1.8]
    peanut[:, 0] += 0.6 * z ** 2                                # a bent, two-lobed bean
    bean = (scaled_to_area(peanut, Fi, 1.6 * area), Fi)

    row1 = [Panel(V0, F, color=COLOR, title=f"lychee, {len(V0) // 1000}k vertices"),
            Panel(apply_texture(Vs, F, whirled), F, color=COLOR, title="whirled (wrap k = 4)")]
    # close-ups: the close-up camera on the whole lit mesh, an inset marking where
    row2 = [Panel(apply_texture(Vs, F, whirled), F, color=COLOR, closeup_radius=0.5,
                  closeup=busy_point(Vs, F, tex.height, VIEW, 0.35),
                  title="whirled lychee, close up")]
    targets = [("avocado", avocado), ("bean", bean)]
    if os.environ.get("GEOTEX_EXAMPLES_QUICK") == "1":
        targets = targets[:1]
    for name, (Vd, Fd) in targets:
        t = time.perf_counter()
        moved, rep = transfer_between_shapes(Vs, F, whirled, Vd, Fd)
        Vt = apply_texture(Vd, Fd, moved)
        print(f"{name}: {len(Vd)} vertices, {time.perf_counter() - t:.1f} s")
        for line in rep.lines():
            print("  " + line)
        ratio = rep.target.mean_element_height / rep.source.mean_element_height
        row1.append(Panel(Vt, Fd, color=TARGET_COLOR,
                          title=f"{name}: heights {100 * (ratio - 1):+.0f}%"))
        c = busy_point(Vd, Fd, moved.height, VIEW, 0.35)
        row2.append(Panel(Vt, Fd, color=TARGET_COLOR, closeup=c, closeup_radius=0.5,
                          title=f"{name}, close up"))
    path = out / "heighttilt_shapes.png"
    with tempfile.TemporaryDirectory() as tmp:
        a = render_panels(row1, Path(tmp) / "a.png", size=(480, 520), up="z")
        b = render_panels(row2, Path(tmp) / "b.png", size=(640, 520), up="z")
        top, bottom = Image.open(a), Image.open(b)
        w = max(top.width, bottom.width)
        canvas = Image.new("RGB", (w, top.height + bottom.height), "white")
        canvas.paste(top, ((w - top.width) // 2, 0))
        canvas.paste(bottom, ((w - bottom.width) // 2, top.height))
        buf = io.BytesIO()
        canvas.save(buf, format="PNG")
    path.write_bytes(buf.getvalue())
    print(f"wrote {path}")


# %%
# Run: the pictures (and, for the examples that make a mesh, a GLB shown in
# the 3D viewer) go to the folder given as the first argument, by
# default ``docs/gallery``.

if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).parents[1] / "docs" / "gallery")
