"""``geotex hpm BASE --image IMG -o OUT``: hierarchical pattern mapping (texture coordinates)."""

from __future__ import annotations

import json
import math
from pathlib import Path

from geotex.cli._common import EXIT_OK, UsageError, flag_error, guard_output
from geotex.cli.relief import add_relief_arguments, check_relief_output, write_relief

HELP = ("texture a closed mesh with patches of one image, coarse to fine (hierarchical "
        "pattern mapping): GLB or OBJ+MTL+PNG with the image itself as texture")


#: Most faces the command refines a coarse base to (hpm takes about a second per 1000 faces).
MAX_REFINED_FACES = 60_000


def register(sub):
    p = sub.add_parser("hpm", help=HELP, description=HELP + ". Face clusters are flattened "
                       "and matched against the image by FFT correlation with the texture "
                       "already placed around them; clusters that fit badly are subdivided. "
                       "The output holds texture coordinates into IMG (no new texture).")
    p.add_argument("base", metavar="BASE", help="closed manifold mesh to texture")
    p.add_argument("--image", required=True, metavar="IMG", help="texture sample (PNG, JPEG; "
                   "RGB or grey)")
    p.add_argument("--scale", type=float, default=None, metavar="S",
                   help="surface length (mm) covered by the image width (default: a quarter "
                        "of the bounding-box diagonal); a base whose faces are too large for "
                        "the image at this scale is refined by exact edge splits (up to "
                        f"{MAX_REFINED_FACES} faces)")
    p.add_argument("--field", default=None, metavar="F.npz",
                   help="direction field from 'geotex field': every patch takes its "
                        "direction, neighbours' continuations within --field-tolerance of it")
    p.add_argument("--orientation", choices=("auto", "field", "neighbours"), default="auto",
                   help="without --field: where the patches' orientation comes from; auto "
                        "(default): a smooth direction field of the surface for a periodic or "
                        "anisotropic image (one orientation over the surface, breaks only at "
                        "the field's singularities), the neighbours for a stochastic one; "
                        "field: the smooth field always; neighbours: propagated from patch "
                        "to patch (the paper's)")
    p.add_argument("--field-tolerance", type=float, default=25.0, metavar="DEG",
                   help="with a field: a neighbour's continuation is turned onto the field's "
                        "direction and kept as a candidate when the turn is at most DEG "
                        "degrees (default 25)")
    p.add_argument("--angle", type=float, default=None, metavar="DEG",
                   help="orientation of the first patch in degrees (default random); with "
                        "the automatic field: the field's turn about the normals")
    p.add_argument("--orientation-spread", default="30", metavar="DEG|any",
                   help="when the orientation comes from the neighbours (a stochastic image, "
                        "or --orientation neighbours): a patch next to textured faces is "
                        "matched only at "
                        "orientations within DEG degrees of its main neighbour's, so the "
                        "orientation carries over as in the paper (default 30); 'any' "
                        "searches every orientation")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--max-error", type=float, default=0.35, metavar="E",
                   help="largest relative matching error accepted before a cluster is "
                        "subdivided (default 0.35; 1 = as bad as random pixels)")
    p.add_argument("--band", type=float, default=0.06, metavar="W",
                   help="width of the band of textured neighbours matched along a patch "
                        "border, as a fraction of the image width (default 0.06; the paper "
                        "widens it for anisotropic and structured patterns; on Spot 0.12 "
                        "left a fifth of the faces to the face level and made the seams where "
                        "the map jumps more visible, see docs/architecture.md)")
    p.add_argument("--face-level", choices=("match", "unfold"), default="match",
                   help="faces left after the finest cluster level: matched against the "
                        "image in small groups, unfolding only those that still match badly "
                        "(default), or all unfolded from a textured neighbour")
    p.add_argument("--structure", choices=("auto", "off"), default="auto",
                   help="auto (default): estimate the image's pattern period and anisotropy; "
                        "a periodic image gets a band of at least half a period, neighbours "
                        "continued by whole periods and no patch split below --min-patch "
                        "periods; an anisotropic one a wider band (stochastic images are "
                        "unaffected); off: ignore them")
    p.add_argument("--min-patch", type=float, default=0.3, metavar="K",
                   help="with a periodic image, a cluster whose children are smaller than K "
                        "periods keeps its best match instead of being split (default 0.3; "
                        "the paper's 1 made the seams worse on Spot; 0 never)")
    p.add_argument("--subpixel", action="store_true",
                   help="refine every match below the pixel and orientation grids (did not "
                        "lower the seams on Spot; off by default)")
    p.add_argument("--report", default=None, metavar="R.json",
                   help="also write per-level counts and matching errors")
    add_relief_arguments(p, what="the mapped image's luminance")
    p.add_argument("-o", "--output", required=True,
                   help="OUT.glb or OUT.obj (textured), OUT.stl or OUT.3mf (with --displace)")
    p.set_defaults(run=run)


def _outputs(args) -> list[Path]:
    out = Path(args.output)
    ext = out.suffix.lower()
    if args.displace is None and ext not in (".glb", ".obj"):
        raise UsageError(f"{out}: hpm writes a textured mesh; use .glb or .obj (a relief "
                         "needs --displace MM)")
    check_relief_output(args, out)
    written = [out]
    if ext == ".obj":
        written += [out.with_name(out.stem + ".mtl"), out.with_name(out.stem + ".png")]
    if args.report:
        if Path(args.report).suffix.lower() != ".json":
            raise UsageError(f"{args.report}: --report writes a .json file")
        written.append(Path(args.report))
    inputs = [args.base, args.image, args.field]
    for path in written:
        guard_output(path, *inputs)
    if len({str(p.resolve()) for p in written}) != len(written):
        raise UsageError("--report must differ from the output files")
    return written


def _refuse_unstorable(reach: float, out: Path, args) -> None:
    """Refuse, before any work, coordinates the output cannot store.

    A GLB stores float32 positions; a relief (``--displace``) is written and
    checked in float32 and refused beyond 1e15 mm by ``geotex displace``'s rule.
    An OBJ is text and takes any finite coordinate.
    """
    import numpy as np

    if args.displace is not None and not reach <= 1e15:
        raise UsageError(f"{args.base}: coordinates reach {reach:.3g} mm, beyond the 1e+15 mm "
                         "a relief (--displace) handles; scale the part down")
    if (args.displace is None and out.suffix.lower() == ".glb"
            and not reach <= float(np.finfo(np.float32).max)):
        raise UsageError(f"{args.base}: coordinates exceed the float32 range of glTF "
                         "positions; scale the part down or write .obj")


def _spread(text: str) -> float | None:
    """``--orientation-spread``: degrees (finite, >= 0) or 'any' (None)."""
    if text.strip().lower() == "any":
        return None
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (value >= 0.0 and value != float("inf")):
        raise UsageError(f"--orientation-spread {text}: give degrees >= 0 or 'any'")
    return value


def _fine_enough(V, F, image, scale: float, args):
    """``(V, F, note)``: the base refined so that a triangle fits in the image (note ''
    when it already does), or a UsageError naming ``--scale`` when that takes too many faces.

    Texture coordinates point into the one image, so a face must be smaller than the
    image; hpm refuses edges averaging more than half of it. Refined to edges of at most
    a quarter of the image's shorter side.
    """
    import numpy as np

    from geotex.errors import InputError
    from geotex.relief import refined_by_edge_splits

    H_img, W_img = image.shape[:2]
    side = scale * min(W_img, H_img) / W_img              # surface length of the shorter side
    elen = float(np.linalg.norm(V[F] - V[np.roll(F, -1, axis=1)], axis=2).mean())
    if not (math.isfinite(elen) and math.isfinite(side)) or elen <= 0.5 * side:
        return V, F, ""
    try:
        r = refined_by_edge_splits(V, F, 0.25 * side, max_faces=MAX_REFINED_FACES)
    except InputError:
        given = "--scale" if args.scale is not None else "the default --scale"
        raise UsageError(
            f"{given} {scale:g} is too small for this mesh: its edges average {elen:.3g}, "
            f"and refining them to fit the image would take more than {MAX_REFINED_FACES} "
            f"faces; give a --scale of at least {2.0 * elen * W_img / min(W_img, H_img):.3g}"
        ) from None
    return r.vertices, r.faces, f"mean edge {elen:.3g}, image side {side:.3g}"


def run(args) -> int:
    import numpy as np

    from geotex.image.hpm import hpm_mesh, hpm_texture, read_hpm_image
    from geotex.io import read_mesh, write_mesh
    from geotex.mesh.record import Mesh
    from geotex.io.atomic import atomic_output
    from geotex.progress import stage_bar

    written = _outputs(args)
    out = written[0]
    if args.scale is not None and not (math.isfinite(args.scale) and args.scale > 0):
        raise UsageError(f"--scale {args.scale!r}: give a positive surface length in mm")
    if args.angle is not None and not math.isfinite(args.angle):
        raise UsageError(f"--angle {args.angle!r}: give a finite angle in degrees")
    if not (math.isfinite(args.band) and 0 < args.band <= 1):
        raise UsageError(f"--band {args.band!r}: give a fraction of the image width in (0, 1]")
    if not (math.isfinite(args.max_error) and args.max_error > 0):
        raise UsageError(f"--max-error {args.max_error!r}: give a positive number")
    mesh = read_mesh(args.base)
    if mesh.n_faces == 0:
        raise UsageError(f"{args.base}: the mesh has no faces")
    V, F = mesh.vertices, mesh.faces
    _refuse_unstorable(float(np.abs(V).max()), out, args)
    image = read_hpm_image(args.image)
    field = None
    if args.field is not None:
        if not args.field.lower().endswith(".npz"):
            raise UsageError(f"--field {args.field}: give a field file (.npz) from 'geotex field'")
        from geotex.fields.store import load_direction_field
        field = load_direction_field(args.field).field
        if field.vectors.shape != (F.shape[0], 3):
            raise UsageError(f"{args.field}: the field has {field.vectors.shape[0]} faces, the "
                             f"mesh {F.shape[0]}; compute it on this mesh with 'geotex field'")
    spread = _spread(args.orientation_spread)
    scale = args.scale
    if scale is None:
        scale = 0.25 * float(np.linalg.norm(np.ptp(V, axis=0)))
    input_faces = int(F.shape[0])
    V, F, refined = _fine_enough(V, F, image, scale, args)
    if refined:
        if field is not None:
            raise UsageError(f"{args.base}: the mesh is refined to fit the pattern ({refined}); "
                             "compute --field on a finer mesh, or give a larger --scale")
        print(f"{args.base}: edges long for the pattern ({refined}): refined by exact edge "
              f"splits (the same surface) to {F.shape[0]} faces")
        mesh = Mesh(V, F, name=mesh.name)
    try:
        with stage_bar(8, "hpm") as bar:
            result = hpm_texture(V, F, image, scale=scale, field=field, angle=args.angle,
                                 seed=args.seed, max_error=args.max_error,
                                 orientation_spread=spread, band_distance=args.band,
                                 face_match=args.face_level == "match",
                                 subpixel=args.subpixel, structure=args.structure == "auto",
                                 min_patch=args.min_patch,
                                 orientation_field={"auto": "auto", "field": "always",
                                                    "neighbours": "never"}[args.orientation],
                                 field_tolerance=args.field_tolerance, progress=bar)
    except Exception as exc:
        from geotex.errors import InputError
        if isinstance(exc, InputError):
            msg = str(exc)
            if msg.startswith("the base mesh"):
                raise UsageError(f"{args.base}: {msg}") from None
            raise flag_error(exc, {"scale": "--scale", "min_patch": "--min-patch",
                                    "field_tolerance": "--field-tolerance"}) from None
        raise
    if args.displace is not None:
        status = write_relief(args, mesh if refined else args.base, args.image, out,
                              result.uv[result.uv_faces])
        if status != EXIT_OK:
            return status
    else:
        write_mesh(out, hpm_mesh(V, F, result, image, name=mesh.name or out.stem))
    if args.report:
        rep = dict(result.report(), base=str(args.base), image=str(args.image),
                   scale=scale, seed=args.seed, faces=int(F.shape[0]), input_faces=input_faces)
        text = json.dumps(rep, indent=2)
        with atomic_output(args.report, "w", encoding="utf-8") as fh:
            fh.write(text + "\n")
    rep = result.report()
    placed = sum(lv["placed"] for lv in rep["levels"])
    print(f"{args.base}: {placed} patches over {F.shape[0]} faces "
          f"(face level: {rep['levels'][-1]['matched_faces']} faces matched, "
          f"{rep['levels'][-1]['filled_faces']} unfolded"
          + (f"; periodic image, {rep['pattern']['period_px']:.0f} px period, "
             f"{sum(lv['forced'] for lv in rep['levels'])} patches kept above the error "
             "threshold" if rep["pattern"].get("periodic") else "")
          + "), "
          f"{result.uv.shape[0]} texture coordinates")
    span = rep["pattern"].get("patch_periods")
    if span is not None:
        print(f"patches span a median {span:.2f} pattern periods"
              + ("; the patches are smaller than the pattern, whose structure may break "
                 "at their borders: a smaller --scale gives larger patches in periods"
                 if span < 1.0 else ""))
    print("wrote " + " and ".join(str(p) for p in written))
    return EXIT_OK

