"""``geotex displace BASE --image HEIGHT --depth MM -o OUT``: height-map relief for printing."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

from geotex.cli._common import (EXIT_NOT_PRINTABLE, EXIT_OK, UsageError, flag_error, guard_output,
                                preload_compiled)

HELP = "displace a part by a height map (image file or library texture): printable STL/3MF"

#: Library words -> flags, for one-line errors that name the flag.
FLAGS = {"depth": "--depth", "scale_u": "--scale-u", "scale_v": "--scale-v",
         "offset_u": "--offset-u", "offset_v": "--offset-v", "rotation": "--rotation",
         "sharpness": "--sharpness", "blend": "--blend", "cap_angle": "--cap-angle",
         "blur": "--blur", "edge_length": "--edge-mm", "size_mm": "--size-mm",
         "bottom_angle": "--mask-bottom", "top_angle": "--mask-top", "width": "--mask-width",
         "box": "--mask-box", "sphere": "--mask-sphere", "normal_cone": "--mask-normal",
         "fill seed faces": "--mask-fill", "fill_angle": "--fill-angle",
         "field": "--field", "field direction": "--field", "refining to edges": "--edge-mm",
         "face selection": "--mask-faces", "the mask": "mask options",
         "mask color": "--mask-color", "mask tolerance": "--mask-tolerance",
         "the uv mapping": "--mapping uv"}


def _numbers(text: str, k: int, flag: str) -> list[float]:
    try:
        vals = [float(x) for x in text.split(",")]
    except ValueError:
        vals = []
    if len(vals) != k or not all(math.isfinite(v) for v in vals):
        raise UsageError(f"{flag} {text!r}: give {k} comma-separated numbers")
    return vals


def register(sub):
    from geotex.displace.choices import CURVES, MAPPINGS, PAINT_TOLERANCE

    p = sub.add_parser("displace", help=HELP, description=HELP + ". The part is refined "
                       "(exact edge splits, creases kept), each vertex reads its height "
                       "through the mapping and moves along the smoothed normal; the result is "
                       "written only when it is printable as stored. Sizes in mm, angles in "
                       "degrees.")
    p.add_argument("base", nargs="?", metavar="BASE",
                   help="part (STL/OBJ/PLY/OFF/3MF/GLB; STEP/STP when gmsh is installed)")
    p.add_argument("--list", action="store_true", help="list the library textures and exit")
    p.add_argument("--image", metavar="HEIGHT.png|NAME",
                   help="height map: an image (white high) or a library name (see --list)")
    p.add_argument("--depth", type=float, metavar="MM", help="relief depth in mm")
    p.add_argument("-o", "--output", help="OUT.stl or OUT.3mf")
    p.add_argument("--mapping", choices=MAPPINGS, default="triplanar",
                   help="how the image is laid on the part (default triplanar)")
    p.add_argument("--size-mm", type=float, default=None, metavar="L",
                   help="scale the part so its largest extent is L mm first")
    p.add_argument("--scale-u", type=float, default=None, metavar="MM",
                   help="mm per image tile across (default 20; uv: UV units, default 1)")
    p.add_argument("--scale-v", type=float, default=None, metavar="MM",
                   help="mm per image tile up (default: --scale-u)")
    p.add_argument("--offset-u", type=float, default=0.0, metavar="MM")
    p.add_argument("--offset-v", type=float, default=0.0, metavar="MM")
    p.add_argument("--rotation", type=float, default=0.0, metavar="DEG",
                   help="turn the image in its plane")
    p.add_argument("--symmetric", action="store_true",
                   help="50%% grey is the surface: relief of DEPTH/2 out and in")
    p.add_argument("--invert", action="store_true", help="dark high instead of white")
    p.add_argument("--blur", type=float, default=0.0, metavar="MM",
                   help="Gaussian blur of the image, mm on the part (uv: pixels)")
    p.add_argument("--sharpness", type=float, default=4.0,
                   help="triplanar blend sharpness (default 4)")
    p.add_argument("--blend", type=float, default=0.15,
                   help="cubic seam blend width, 0-1 (default 0.15)")
    p.add_argument("--axis", choices=("x", "y", "z"), default="z",
                   help="cylindrical/spherical axis (default z)")
    p.add_argument("--cap-angle", type=float, default=20.0, metavar="DEG",
                   help="cylindrical: faces within DEG of the axis are caps, projected flat")
    p.add_argument("--field", default=None, metavar="X,Y,Z|smooth|curvature",
                   help="pgp and lapped: the direction the image's up follows (default "
                   "0,0,1); pgp also takes smooth (smoothest cross field) or curvature")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--faces", type=int, default=1_000_000, metavar="N",
                   help="approximate refined face count (default 1000000)")
    p.add_argument("--edge-mm", type=float, default=None, metavar="MM",
                   help="longest refined edge instead of --faces")
    p.add_argument("--max-faces", type=int, default=6_000_000, metavar="N",
                   help="safety cap on the refined mesh (default 6000000)")
    p.add_argument("--decimate", type=int, default=None, metavar="N",
                   help="QEM-decimate the result to N faces")
    p.add_argument("--mask-bottom", type=float, default=5.0, metavar="DEG",
                   help="faces within DEG of facing down stay flat (default 5; 0: off)")
    p.add_argument("--mask-top", type=float, default=0.0, metavar="DEG",
                   help="faces within DEG of facing up stay flat (default 0: off)")
    p.add_argument("--mask-faces", metavar="FILE.json|PAINTED.ply|PAINTED.obj",
                   help="face selection: JSON face indices, or the part painted in any editor "
                   "(PLY with per-face or per-vertex colours, OBJ with v x y z r g b): faces "
                   "whose colour is not the part's most common colour are selected (vertex "
                   "colours: 2 of 3 corners); the painted file may be re-indexed, faces are "
                   "matched by nearest centroid")
    p.add_argument("--mask-color", metavar="R,G,B", default=None,
                   help="with a painted --mask-faces: select this paint (0-255) instead")
    p.add_argument("--mask-tolerance", type=float, default=PAINT_TOLERANCE, metavar="T",
                   help="colours match when no channel (0-255) differs by more than T "
                   f"(default {PAINT_TOLERANCE:g})")
    p.add_argument("--mask-box", metavar="X0,Y0,Z0,X1,Y1,Z1", help="select faces in a box (mm)")
    p.add_argument("--mask-sphere", metavar="X,Y,Z,R", help="select faces in a sphere (mm)")
    p.add_argument("--mask-normal", metavar="X,Y,Z,DEG",
                   help="select faces whose normal is within DEG of X,Y,Z")
    p.add_argument("--mask-fill", metavar="F1,F2,...",
                   help="select faces reached from these faces across edges up to --fill-angle")
    p.add_argument("--fill-angle", type=float, default=20.0, metavar="DEG")
    p.add_argument("--mask-mode", choices=("include", "exclude"), default="include",
                   help="texture only the selected faces (include) or all but them")
    p.add_argument("--mask-width", type=float, default=0.0, metavar="MM",
                   help="soft mask border width (default 0: hard)")
    p.add_argument("--mask-curve", choices=CURVES, default="smoothstep")
    p.add_argument("--step-quality", choices=("coarse", "standard", "fine"), default="standard",
                   help="STEP tessellation preset")
    p.add_argument("--keep-failed", action="store_true",
                   help="if not printable, still write NAME.NOT-PRINTABLE.EXT (exit 1)")
    p.add_argument("--report", default=None, metavar="FILE.json", help="also write statistics")
    p.set_defaults(run=run)


def _list() -> int:
    from geotex.displace.library import library_descriptions

    for name, text in library_descriptions().items():
        print(f"{name:15s} {text}")
    return EXIT_OK


def run(args) -> int:
    if args.list:
        return _list()
    from geotex.displace.library import library_names
    from geotex.printing import PRINT_FORMATS

    for flag, val in (("BASE", args.base), ("--image", args.image), ("--depth", args.depth),
                      ("-o", args.output)):
        if val is None:
            raise UsageError(f"{flag} is required (or use --list)")
    base = Path(args.base)
    if not base.is_file():
        raise UsageError(f"{base}: no such file")
    image_is_file = args.image not in library_names()
    out = guard_output(args.output, args.base, args.image if image_is_file else None,
                       args.mask_faces)
    if out.suffix.lower() not in PRINT_FORMATS:
        raise UsageError(f"{out}: cannot write a print as '{out.suffix}'; use .stl or .3mf")
    if image_is_file and not Path(args.image).is_file():
        raise UsageError(f"--image {args.image}: no such image file or library texture "
                         "(see 'geotex displace --list')")
    if not (math.isfinite(args.depth) and args.depth > 0):
        raise UsageError(f"--depth {args.depth}: give a positive depth in mm")
    if args.size_mm is not None and not (0 < args.size_mm <= 10000):
        raise UsageError(f"--size-mm {args.size_mm}: give a size in (0, 10000] mm")
    if args.faces < 100:
        raise UsageError(f"--faces {args.faces}: give at least 100")
    report_path = None
    if args.report is not None:
        report_path = guard_output(args.report, args.base)
        if report_path.suffix.lower() != ".json":
            raise UsageError(f"{report_path}: --report needs a .json file name")
    field = args.field
    if field is not None and field not in ("smooth", "curvature"):
        field = _numbers(field, 3, "--field")
    mask_color = None
    if args.mask_color is not None:
        if args.mask_faces is None:
            raise UsageError("--mask-color needs a painted --mask-faces PLY/OBJ file")
        mask_color = _numbers(args.mask_color, 3, "--mask-color")
        if not all(0 <= v <= 255 for v in mask_color):
            raise UsageError(f"--mask-color {args.mask_color!r}: give R,G,B in 0-255")
    if not (math.isfinite(args.mask_tolerance) and 0 <= args.mask_tolerance <= 255):
        raise UsageError(f"--mask-tolerance {args.mask_tolerance}: give a number in 0-255")
    if args.mask_faces is not None and not Path(args.mask_faces).is_file():
        raise UsageError(f"--mask-faces {args.mask_faces}: no such file")
    preload_compiled(relief=True)
    from geotex.displace import DISPLACE_STAGES, displace_file, mask_options
    from geotex.errors import InputError, NotPrintableError
    from geotex.progress import stage_bar

    try:
        masks = mask_options(
            bottom_angle=args.mask_bottom, top_angle=args.mask_top,
            box=_numbers(args.mask_box, 6, "--mask-box") if args.mask_box else None,
            sphere=_numbers(args.mask_sphere, 4, "--mask-sphere") if args.mask_sphere else None,
            normal_cone=(_numbers(args.mask_normal, 4, "--mask-normal")
                         if args.mask_normal else None),
            fill_seeds=([int(v) for v in _numbers(args.mask_fill, len(args.mask_fill.split(",")),
                                                  "--mask-fill")] if args.mask_fill else ()),
            fill_angle=args.fill_angle, select_mode=args.mask_mode, width=args.mask_width,
            curve=args.mask_curve)
        opts = dict(mapping=args.mapping, scale_u=args.scale_u, scale_v=args.scale_v,
                    offset_u=args.offset_u, offset_v=args.offset_v, rotation=args.rotation,
                    sharpness=args.sharpness, blend=args.blend, axis=args.axis,
                    cap_angle=args.cap_angle, symmetric=args.symmetric, blur=args.blur,
                    invert=args.invert, masks=masks, edge_length=args.edge_mm,
                    target_faces=args.faces, max_faces=args.max_faces,
                    decimate_to=args.decimate, field=field, seed=args.seed,
                    mask_file=args.mask_faces, mask_color=mask_color,
                    mask_tolerance=args.mask_tolerance)
        status = EXIT_OK
        with stage_bar(len(DISPLACE_STAGES), "displace") as bar:
            try:
                res = displace_file(args.base, args.image, out, depth=args.depth,
                                    size_mm=args.size_mm, step_quality=args.step_quality,
                                    progress=bar, **opts)
            except NotPrintableError as exc:
                print(f"geotex: error: {out}: not written, not printable as stored "
                      f"({'; '.join(exc.report.reasons)})", file=sys.stderr)
                if not args.keep_failed:
                    return EXIT_NOT_PRINTABLE
                kept = out.with_name(f"{out.stem}.NOT-PRINTABLE{out.suffix}")
                res = displace_file(args.base, args.image, kept, depth=args.depth,
                                    size_mm=args.size_mm, step_quality=args.step_quality,
                                    force=True, **opts)
                print(f"wrote {kept} for inspection (NOT printable)")
                status, out = EXIT_NOT_PRINTABLE, kept
    except InputError as exc:
        raise flag_error(exc, FLAGS) from None
    for w in res.warnings:
        print(f"geotex: warning: {w}", file=sys.stderr)
    s = res.stats
    if "mask_file_faces" in s:
        print(f"face selection {args.mask_faces}: {s['mask_file_faces']} base faces selected")
    if status == EXIT_OK:
        print(f"wrote {out}: {s['faces']} faces, {args.mapping} mapping, depth "
              f"{args.depth:g} mm, printable as written (checked on the file's own coordinates)")
    if report_path is not None:
        from geotex.io.atomic import atomic_output

        with atomic_output(report_path, "w") as fh:
            json.dump({"unit": "mm", "stats": s, "warnings": list(res.warnings),
                       "check": res.report.to_dict() if res.report is not None else None},
                      fh, indent=2, sort_keys=True, default=float)
        print(f"wrote {report_path}")
    return status
