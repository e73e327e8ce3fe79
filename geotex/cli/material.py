"""``geotex material tile|map``: material-space (s, t, m) tiles and their mapping over a mesh."""

from __future__ import annotations

import json
import math
import time
from pathlib import Path

from geotex.cli._common import EXIT_OK, UsageError, flag_error, guard_output
from geotex.cli.relief import add_relief_arguments, check_relief_output, write_relief
from geotex.cli.field import _constraints, add_field_source_arguments, field_from_args

HELP = "material-space textures: build an (s, t, m) tile from two images, map it over a mesh"
TEXTURED = (".glb", ".obj")
#: keys of a constraint entry that only the material field reads
MATERIAL_KEYS = ("material", "vertex", "stroke")


def register(sub):
    p = sub.add_parser("material", help=HELP, description=HELP + ".")
    msub = p.add_subparsers(dest="material_command", metavar="ACTION", parser_class=type(p))
    t = msub.add_parser("tile", aliases=["build"], help="build a periodic (s, t, m) tile",
                        description="Make both images tileable (graph cut), morph their "
                        "feature masks by level-set advection, synthesize every layer under "
                        "its morphed mask from both inputs and blend them; write TILE.npz. "
                        "With one image: a periodicity-hiding tile (layers share the mask).")
    t.add_argument("images", nargs="+", metavar="IMAGE",
                   help="A.png B.png (m = 0 and m = 1), or one image for a "
                        "periodicity-hiding tile")
    t.add_argument("-o", "--output", required=True, help="tile file to write (.npz)")
    t.add_argument("--size", default="128", metavar="PX",
                   help="tile side in texels (multiple of 4, >= 32; default 128)")
    t.add_argument("--layers", default=None, metavar="K",
                   help="layers along m (default 8; 4 for one image)")
    t.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    t.add_argument("--mask-a", metavar="MA.png", default=None,
                   help="feature mask image of A (white = feature), same size as A")
    t.add_argument("--mask-b", metavar="MB.png", default=None,
                   help="feature mask image of B (white = feature), same size as B")
    t.add_argument("--threshold-a", default=None, metavar="T",
                   help="luminance threshold in [0, 1] for A's mask (default Otsu)")
    t.add_argument("--threshold-b", default=None, metavar="T",
                   help="luminance threshold in [0, 1] for B's mask (default Otsu)")
    t.add_argument("--blend", choices=("linear", "select"), default="select",
                   help="combine the two syntheses of a layer by a histogram-keeping selection "
                        "along a smooth noise (default: closer to the inputs' histograms than a "
                        "cross-fade) or by the paper's linear blend")
    t.add_argument("--preview", metavar="SLICES.png", default=None,
                   help="also write a picture of the m-slices and their masks")
    t.add_argument("--json", action="store_true", help="print one JSON object")
    t.set_defaults(run=run_tile)

    m = msub.add_parser("map", aliases=["apply"], help="map a tile over a mesh (baked atlas)",
                        description="Periodic global parameterization (s, t) steered by the "
                        "field and --scale, material m interpolated from the constraints' "
                        "'material' values (or a ramp along --up / z); the (s, t, m) lookup "
                        "is baked into a texture atlas: OUT.glb, or OUT.obj + .mtl + .png.")
    m.add_argument("mesh", help="mesh file")
    m.add_argument("--tile", required=True, metavar="TILE.npz", help="tile from 'material tile'")
    add_field_source_arguments(m)
    m.add_argument("--scale", required=True, metavar="MM",
                   help="tile size in surface units (mm); constraint scales override it")
    m.add_argument("--resolution", default="2048", metavar="PX",
                   help="atlas texture size (default 2048)")
    m.add_argument("--hide-periodicity", default=None, metavar="AMP",
                   help="modulate m by smooth noise of this amplitude in [0, 1] (paper Fig. 14)")
    m.add_argument("--wavelength", default=None, metavar="MM",
                   help="wavelength of the --hide-periodicity noise (default 3 x --scale)")
    m.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    add_relief_arguments(m, what="the baked texture's luminance", size=False)
    m.add_argument("-o", "--output", required=True,
                   help="OUT.glb or OUT.obj, or OUT.stl / OUT.3mf with --displace")
    m.add_argument("--json", action="store_true", help="print one JSON object")
    m.set_defaults(run=run_map)
    p.set_defaults(run=_no_action(p))


def _no_action(p):
    def run(args) -> int:
        raise UsageError("material needs an action: 'tile' or 'map' (see 'geotex material "
                         "--help')")
    return run


def _number(text, flag: str, *, lo=None, hi=None, integer=False, positive=False):
    try:
        value = int(text) if integer else float(text)
    except (TypeError, ValueError):
        raise UsageError(f"{flag} {text!r}: give a{'n integer' if integer else ' number'}"
                         ) from None
    if not math.isfinite(value) or (positive and not value > 0) or \
            (lo is not None and value < lo) or (hi is not None and value > hi):
        rng = "a positive value" if positive else f"a value in [{lo}, {hi}]" \
            if hi is not None else f"a value >= {lo}"
        raise UsageError(f"{flag} {text!r}: give {rng}")
    return value


def _image(path: str, flag: str):
    from geotex.image.patches import load_image
    from geotex.io.limits import RefusedInput

    try:
        return load_image(path)
    except RefusedInput as exc:
        raise UsageError(f"{flag} {path}: {exc}") from None


def run_tile(args) -> int:
    import numpy as np

    from geotex.errors import InputError
    from geotex.image.material.tile import (build_material_tile, build_periodicity_tile,
                                            save_tile, tile_slices_image)
    from geotex.io.atomic import atomic_output
    from geotex.io.images import texture_to_png_bytes
    from geotex.progress import stage_bar

    if len(args.images) > 2:
        raise UsageError(f"material tile takes one or two images, got {len(args.images)}")
    out = guard_output(args.output, *args.images, args.mask_a, args.mask_b)
    if out.suffix.lower() != ".npz":
        raise UsageError(f"{out}: tile files are .npz; use a .npz file name")
    preview = None
    if args.preview is not None:
        preview = guard_output(args.preview, *args.images, args.mask_a, args.mask_b)
        if preview.suffix.lower() != ".png":
            raise UsageError(f"--preview {preview}: give a .png file name")
    size = _number(args.size, "--size", integer=True, lo=32)
    if size % 4:
        raise UsageError(f"--size {size}: give a multiple of 4 (three pyramid levels)")
    single = len(args.images) == 1
    layers = _number(args.layers, "--layers", integer=True, lo=2) if args.layers else (
        4 if single else 8)
    if layers > 64:
        raise UsageError(f"--layers {layers}: give at most 64 layers")
    thr = [None if t is None else _number(t, flag, lo=0.0, hi=1.0)
           for t, flag in ((args.threshold_a, "--threshold-a"),
                           (args.threshold_b, "--threshold-b"))]
    if single and (args.mask_b is not None or args.threshold_b is not None):
        raise UsageError("--mask-b/--threshold-b need a second image")
    imgs = [_image(p, p) for p in args.images]
    masks = [None if p is None else _image(p, flag)
             for p, flag in ((args.mask_a, "--mask-a"), (args.mask_b, "--mask-b"))]
    for k, (mk, flag) in enumerate(zip(masks, ("--mask-a", "--mask-b"))):
        if mk is not None and k < len(imgs) and mk.shape[:2] != imgs[k].shape[:2]:
            raise UsageError(f"{flag} {getattr(args, flag[2:].replace('-', '_'))}: the mask is "
                             f"{mk.shape[1]} x {mk.shape[0]} pixels but "
                             f"{args.images[k]} is {imgs[k].shape[1]} x {imgs[k].shape[0]}; "
                             "give a mask of the same size")
    t0 = time.perf_counter()
    stages = 2 + layers if single else 4 + 2 * layers
    try:
        with stage_bar(stages, "material tile") as bar:
            if single:
                tile = build_periodicity_tile(imgs[0], size=size, layers=layers, seed=args.seed,
                                              mask=masks[0], threshold=thr[0], progress=bar)
            else:
                tile = build_material_tile(imgs[0], imgs[1], size=size, layers=layers,
                                           seed=args.seed, mask_a=masks[0], mask_b=masks[1],
                                           threshold_a=thr[0], threshold_b=thr[1],
                                           blend=args.blend, progress=bar)
    except InputError as exc:
        raise flag_error(exc, {"threshold": "--threshold-a/-b"}) from None
    meta = dict(tile.metadata)
    meta["inputs"] = [str(p) for p in args.images]
    tile = type(tile)(layers=tile.layers, masks=tile.masks, metadata=meta)
    save_tile(out, tile)
    if preview is not None:
        with atomic_output(preview, "wb") as fh:
            fh.write(texture_to_png_bytes(tile_slices_image(tile)))
    elapsed = time.perf_counter() - t0
    summary = {"output": str(out), "kind": meta["kind"], "size": size, "layers": layers,
               "seconds": round(elapsed, 3), "mask_areas": meta.get("mask_areas"),
               "histogram_distance": meta.get("histogram_distance"),
               "cross_fade_histogram_distance": meta.get("cross_fade_histogram_distance"),
               "preview": None if preview is None else str(preview)}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"{meta['kind']} tile: {layers} layers of {size} x {size} texels in "
              f"{elapsed:.1f} s")
        if meta.get("histogram_distance") is not None:
            h = np.mean(meta["histogram_distance"][1:-1]) if layers > 2 else 0.0
            c = np.mean(meta["cross_fade_histogram_distance"][1:-1]) if layers > 2 else 0.0
            print(f"histogram distance (inner layers, mean): {h:.4f}; plain cross-fade: "
                  f"{c:.4f}")
        print(f"wrote {out}" + ("" if preview is None else f" and {preview}"))
    return EXIT_OK


def run_map(args) -> int:
    from geotex.errors import InputError
    from geotex.image.material.mapping import (bake_material_texture, default_material,
                                               material_locks, modulated_material)
    from geotex.image.material.tile import load_tile
    from geotex.io import read_mesh, write_mesh
    from geotex.param.pgp import periodic_parameterization
    from geotex.progress import stage_bar

    out = guard_output(args.output, args.mesh, args.tile, args.constraints)
    if args.displace is None and out.suffix.lower() not in TEXTURED:
        raise UsageError(f"{out}: write a textured .glb or .obj (a relief needs --displace MM)")
    check_relief_output(args, out)
    scale = _number(args.scale, "--scale", positive=True)
    res = _number(args.resolution, "--resolution", integer=True, lo=64)
    if res > 8192:
        raise UsageError(f"--resolution {res}: give at most 8192")
    amp = None if args.hide_periodicity is None else _number(
        args.hide_periodicity, "--hide-periodicity", lo=0.0, hi=1.0)
    wave = None if args.wavelength is None else _number(args.wavelength, "--wavelength",
                                                        positive=True)
    if wave is not None and amp is None:
        raise UsageError("--wavelength needs --hide-periodicity")
    try:
        tile = load_tile(args.tile)
    except InputError as exc:
        raise UsageError(f"--tile {exc}") from None
    mesh = read_mesh(args.mesh)
    V, F = mesh.vertices, mesh.faces
    if mesh.n_faces == 0:
        raise UsageError(f"{args.mesh}: the mesh has no faces")
    t0 = time.perf_counter()
    with stage_bar(5, "material map") as bar:
        bar("field")
        entries = [] if args.constraints is None else _constraints(args.constraints)
        if args.constraints is not None:
            # orientation / scale entries go to the field, material entries to m
            from geotex.fields.directions import constraint_scale_field, smooth_direction_field

            plain = [{k: v for k, v in c.items() if k not in MATERIAL_KEYS}
                     for c in entries if "direction" in c and ("face" in c or "point" in c)]
            try:
                field = smooth_direction_field(V, F, symmetry=4, constraints=plain,
                                               seed=args.seed)
                scale_field = constraint_scale_field(V, F, plain)
            except InputError as exc:
                raise UsageError(f"{args.constraints}: {exc}") from None
            method = "smooth"
        else:
            field, scale_field, method = field_from_args(args, V, F, 4)
        bar("parameterization")
        try:
            params = periodic_parameterization(V, F, field, seed=args.seed,
                                               scale=scale if scale_field is None
                                               else scale_field)
        except InputError as exc:
            raise flag_error(exc, {"scale": "--scale"}) from None
        bar("material")
        try:
            lv, lval = material_locks(V, F, entries)
        except InputError as exc:
            raise UsageError(f"{args.constraints}: {exc}") from None
        if lv.size:
            from geotex.fields.scalar import material_field

            material = material_field(V, F, lv, lval)
            how = f"{lv.size} constrained vertices"
        else:
            up = [0.0, 0.0, 1.0]
            if args.up is not None:
                up = [float(x) for x in args.up.split(",")]
            material = default_material(V, F, up=up)
            how = "ramp along " + ",".join(f"{x:g}" for x in up)
        if amp is not None:
            material = modulated_material(V, material, amplitude=amp,
                                          wavelength=3.0 * scale if wave is None else wave,
                                          seed=args.seed)
        bar("bake")
        textured = bake_material_texture(V, F, params, material, tile, field=field,
                                         resolution=res, name=Path(args.mesh).stem)
        bar("write")
        if args.displace is None:
            write_mesh(out, textured)
    if args.displace is not None:
        status = write_relief(args, args.mesh, textured.texture, out,
                              textured.uv[textured.uv_faces])
        if status != EXIT_OK:
            return status
    elapsed = time.perf_counter() - t0
    summary = {"mesh": str(args.mesh), "output": str(out), "faces": int(F.shape[0]),
               "field": method, "material": how,
               "material_range": [float(material.min()), float(material.max())],
               "singular_faces": int(params.singular.sum()),
               "seam_residual": params.seam_residual, "seconds": round(elapsed, 3),
               "texture": list(textured.texture.shape[:2])}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"{args.mesh}: {F.shape[0]} faces, {method} field, material {how} "
              f"(m {material.min():.2f}..{material.max():.2f}), "
              f"{int(params.singular.sum())} singular faces blended; {elapsed:.1f} s")
        print(f"wrote {out}")
    return EXIT_OK

