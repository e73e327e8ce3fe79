"""``geotex lapped BASE --image IMG -o OUT``: lapped image textures, or a printable relief."""

from __future__ import annotations

import math
import sys
from pathlib import Path

from geotex.cli._common import EXIT_NOT_PRINTABLE, EXIT_OK, UsageError, guard_output

HELP = "paste an image texture over a mesh (lapped textures): textured GLB/OBJ or relief STL/3MF"
TEXTURED = (".glb", ".obj")
PRINTS = (".stl", ".3mf")


def register(sub):
    p = sub.add_parser("lapped", help=HELP, description=HELP + ". Texture patches cut from the "
                       "image are pasted through field-aligned local parameterizations until "
                       "every face is covered; the pastes are composited into a packed texture "
                       "atlas (OUT.glb, or OUT.obj + OUT.mtl + OUT.png), or, with --displace, "
                       "used as a height field on a refined copy of the mesh (OUT.stl/.3mf, "
                       "written only when it passes the printability check).")
    p.add_argument("base", metavar="BASE", help="mesh to texture")
    p.add_argument("--image", required=True, metavar="IMG", help="example texture (PNG, JPEG)")
    p.add_argument("--mask", default="splotch", metavar="splotch|circle|FILE",
                   help="texture patch shape: a predefined splotch or circle, or a mask image "
                        "(white or opaque = inside); default splotch")
    p.add_argument("--field", default="isotropic", metavar="isotropic|up|curvature|FILE",
                   help="texture orientation: isotropic (random per paste, default), up (the "
                        "--up direction projected onto the surface), curvature (maximal "
                        "principal directions), a field file from 'geotex field' (.npz) or "
                        "constraints (.json, as for 'geotex field --constraints')")
    p.add_argument("--up", default="0,0,1", metavar="X,Y,Z",
                   help="global up direction for --field up (default 0,0,1)")
    p.add_argument("--scale", type=float, default=None, metavar="S",
                   help="surface length of one texture patch (default 0.15 x the bounding-box "
                        "diagonal); multiplies the scale field of a field file that has one")
    p.add_argument("--patches", type=int, default=1, metavar="K",
                   help="number of texture patches cut from the image at random (default 1)")
    p.add_argument("--patch-size", type=int, default=None, metavar="PX",
                   help="side of the square patches in pixels (default: the image)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--resolution", type=int, default=1024, metavar="PX",
                   help="atlas texture size (default 1024)")
    p.add_argument("--displace", type=float, default=None, metavar="DEPTH",
                   help="write a printable relief instead: light parts raised by up to DEPTH")
    p.add_argument("--invert", action="store_true", help="with --displace: dark parts raised")
    p.add_argument("--pastes", metavar="FILE.npz", default=None,
                   help="also write the paste records (faces and texture coordinates)")
    p.add_argument("-o", "--output", required=True, help="OUT.glb or OUT.obj (textured), "
                   "OUT.stl or OUT.3mf (with --displace)")
    p.set_defaults(run=run)


def _vector(text: str) -> list[float]:
    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3 or not all(math.isfinite(v) for v in values) or not any(values):
        raise UsageError(f"--up {text!r}: give three comma-separated numbers, e.g. 0,0,1")
    return values


def _outputs(args) -> tuple[Path, list[Path]]:
    out = Path(args.output)
    ext = out.suffix.lower()
    if args.displace is not None:
        if ext not in PRINTS:
            raise UsageError(f"{out}: --displace writes a printable solid; use .stl or .3mf")
        if not (math.isfinite(args.displace) and args.displace > 0):
            raise UsageError(f"--displace {args.displace!r}: give a positive depth")
    elif ext not in TEXTURED:
        hint = " (add --displace DEPTH for a printable relief)" if ext in PRINTS else ""
        raise UsageError(f"{out}: a lapped texture is written as .glb or .obj{hint}")
    inputs = [args.base, args.image]
    if args.mask not in ("splotch", "circle"):
        inputs.append(args.mask)
    if args.field.lower().endswith((".npz", ".json")):
        inputs.append(args.field)
    written = [out]
    if ext == ".obj":
        written += [out.with_name(out.stem + ".mtl"), out.with_name(out.stem + ".png")]
    if args.pastes:
        if Path(args.pastes).suffix.lower() != ".npz":
            raise UsageError(f"{args.pastes}: paste records are .npz files")
        written.append(Path(args.pastes))
    for path in written:
        guard_output(path, *inputs)
    if len({str(p.resolve()) for p in written}) != len(written):
        raise UsageError("--pastes must differ from the output files")
    return out, written


def _field(args, V, F):
    """(field or None, per-face scale multiplier or None)."""
    import numpy as np

    kind = args.field
    low = kind.lower()
    if low == "isotropic":
        return None, None
    if low == "up":
        from geotex.fields.directions import projected_direction_field
        return projected_direction_field(V, F, _vector(args.up))[0], None
    if low == "curvature":
        from geotex.fields.directions import principal_direction_field
        from geotex.fields.frames import face_frames, tangent_angles
        from geotex.fields.singularities import singularities
        from geotex.fields.directions import DirectionField
        vec = principal_direction_field(V, F).directions
        T1, T2, N = face_frames(V, F)
        theta = tangent_angles(T1, T2, vec)
        return DirectionField(vectors=vec, symmetry=2, values=np.exp(2j * theta),
                              singularities=tuple(singularities(V, F, vec, symmetry=2)),
                              normals=N, constrained=np.zeros(0, np.int64)), None
    if low.endswith(".npz"):
        from geotex.fields.scalar import vertex_to_face
        from geotex.fields.store import load_direction_field
        ff = load_direction_field(kind)
        if ff.field.vectors.shape != (F.shape[0], 3):
            raise UsageError(f"{kind}: the field has {ff.field.vectors.shape[0]} faces, the mesh "
                             f"{F.shape[0]}; compute it on this mesh with 'geotex field'")
        scale = None
        if ff.scale is not None and ff.scale.shape == (V.shape[0],):
            scale = vertex_to_face(F, ff.scale)
        return ff.field, scale
    if low.endswith(".json"):
        from geotex.cli.field import _constraints
        from geotex.fields.directions import constraint_scale_field, smooth_direction_field
        from geotex.fields.scalar import vertex_to_face
        cons = _constraints(kind)
        field = smooth_direction_field(V, F, symmetry=1, constraints=cons, seed=args.seed)
        scale = None
        if any(isinstance(c, dict) and c.get("scale") is not None for c in cons):
            vs = constraint_scale_field(V, F, cons)
            scale = vertex_to_face(F, vs)
        return field, scale
    raise UsageError(f"--field {kind!r}: give isotropic, up, curvature, FILE.npz or FILE.json")


def _save_records(args, lapped, written) -> None:
    """Write the paste records last; on failure remove the files just written."""
    if not args.pastes:
        return
    from geotex.image.records import save_lapped
    try:
        save_lapped(args.pastes, lapped)
    except BaseException:
        for path in written[:-1]:
            path.unlink(missing_ok=True)
        raise


def run(args) -> int:
    from geotex.image.lapped import default_scale, lapped_texture
    from geotex.image.patches import texture_patches
    from geotex.io import read_mesh, write_mesh

    out, written = _outputs(args)
    if args.patches < 1:
        raise UsageError(f"--patches {args.patches}: give at least 1")
    if args.scale is not None and not (math.isfinite(args.scale) and args.scale > 0):
        raise UsageError(f"--scale {args.scale!r}: give a positive surface length")
    mesh = read_mesh(args.base)
    if mesh.n_faces == 0:
        raise UsageError(f"{args.base}: the mesh has no faces")
    V, F = mesh.vertices, mesh.faces
    patches = texture_patches(args.image, mask=args.mask, count=args.patches,
                              size=args.patch_size, seed=args.seed)
    field, field_scale = _field(args, V, F)
    if field_scale is not None:
        scale = field_scale * (1.0 if args.scale is None else args.scale)
    else:
        scale = default_scale(V) if args.scale is None else args.scale

    from tqdm import tqdm
    bar = tqdm(total=F.shape[0], desc="lapped", unit="face", leave=False,
               disable=not sys.stderr.isatty(), file=sys.stderr)

    def on_paste(n, covered, total):
        bar.n = covered
        bar.set_postfix_str(f"{n} pastes", refresh=True)

    try:
        lapped = lapped_texture(V, F, patches, field=field, scale=scale, seed=args.seed,
                                on_paste=on_paste)
        if args.displace is not None:
            bar.set_description("relief")
            from geotex.image.displace import displace
            from geotex.printing import export_printable
            from geotex.check.report import check_mesh
            Vd, Fd = displace(V, F, lapped, depth=args.displace, invert=args.invert)
            report = check_mesh(Vd, Fd)
            bar.close()
            if not report.printable:
                print(f"geotex: error: the relief is not printable ({'; '.join(report.reasons)});"
                      " try a smaller --displace or a larger --scale", file=sys.stderr)
                return EXIT_NOT_PRINTABLE
            export_printable(out, Vd, Fd, name=mesh.name or out.stem, report=report)
            _save_records(args, lapped, written)
            print(f"{args.base}: {lapped.n_pastes} pastes; relief of {Fd.shape[0]} faces, "
                  f"depth {args.displace:g}, printable")
        else:
            bar.set_description("atlas")
            from geotex.image.atlas import textured_mesh
            textured = textured_mesh(V, F, lapped, resolution=args.resolution,
                                     name=mesh.name or out.stem)
            bar.close()
            write_mesh(out, textured)
            _save_records(args, lapped, written)
            print(f"{args.base}: {lapped.n_pastes} pastes over {F.shape[0]} faces; atlas "
                  f"{textured.texture.shape[1]}x{textured.texture.shape[0]} with "
                  f"{textured.metadata['atlas_charts']} charts")
    finally:
        bar.close()
    print("wrote " + " and ".join(str(p) for p in written))
    return EXIT_OK
