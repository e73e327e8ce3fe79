"""``geotex heighttilt extract | apply | edit | transfer``: height-and-tilt textures."""

from __future__ import annotations

from contextlib import contextmanager, suppress
from pathlib import Path

from geotex.cli._common import EXIT_OK, UsageError, guard_output

HELP = "extract, apply, edit and transfer height-and-tilt geometric textures"


def register(sub):
    p = sub.add_parser("heighttilt", help=HELP, description=HELP + ".")
    hs = p.add_subparsers(dest="heighttilt_command", metavar="ACTION", required=True,
                          parser_class=type(p))

    e = hs.add_parser("extract", help="texture of a detailed mesh over a smooth base",
                      description="Extract the height-and-tilt texture of TEXTURED over a "
                      "base: --base (same connectivity) or implicit mean-curvature-flow steps.")
    e.add_argument("textured", help="detailed mesh file")
    src = e.add_mutually_exclusive_group()
    src.add_argument("--base", help="base mesh file with the same connectivity")
    src.add_argument("--smooth-steps", type=int, default=3,
                     help="mean-curvature-flow steps for the base (default 3)")
    e.add_argument("-o", "--output", required=True, help="texture file to write (.npz)")
    e.add_argument("--base-out", help="also write the base mesh to this file")
    e.set_defaults(run=run_extract)

    a = hs.add_parser("apply", help="put a texture on a base mesh",
                      description="Reconstruct the detailed mesh from BASE and the texture. "
                      "BASE may be a deformed or resized copy of the base the texture was "
                      "extracted on (same connectivity); give that one with --original to "
                      "keep every element's height and lean angle.")
    a.add_argument("texture", help="texture file (.npz)")
    a.add_argument("--base", required=True, help="base mesh file (the texture's connectivity)")
    a.add_argument("--original", metavar="BASE0",
                   help="the base the texture was extracted on (e.g. from --base-out), when "
                   "BASE is a deformed copy of it")
    a.add_argument("-o", "--output", required=True, help="mesh file to write")
    a.set_defaults(run=run_apply)

    t = hs.add_parser("transfer", help="carry a texture onto another base mesh",
                      description="Transfer a texture from its base (--source-base) onto "
                      "the target base.  --map sphere (for a target of another shape; both "
                      "bases closed genus 0): both bases are mapped near-conformally onto the "
                      "unit sphere, aligned by principal axes or --landmarks, and the texture "
                      "is resampled through that map.  --map closest (for a target that nearly "
                      "coincides with the source base): every target vertex takes the closest "
                      "point of the source base.  The tilt is integrated along target edges "
                      "either way.  With --planar the source is a flat texture in the XY "
                      "plane, tiled over the (refined) target through field-aligned patch "
                      "parameterizations.")
    t.add_argument("texture", help="texture file (.npz)")
    t.add_argument("--source-base", required=True, help="the base mesh the texture lives on")
    t.add_argument("--target-base", "--target", dest="target", required=True, metavar="MESH",
                   help="base mesh to receive the texture")
    t.add_argument("--map", choices=("auto", "closest", "sphere"), default="auto",
                   help="correspondence: sphere (different shapes), closest (nearly the same "
                   "surface); auto (default) picks closest when every target vertex lies within "
                   "2%% of the source base's bounding-box diagonal of it, else sphere")
    t.add_argument("--landmarks", metavar="L.json",
                   help="with --map sphere: JSON list of [[sx, sy, sz], [tx, ty, tz]] pairs of "
                   "corresponding source and target points (at least two)")
    t.add_argument("--samples", type=int, default=5,
                   help="samples per edge for the tilt integrals (default 5)")
    t.add_argument("-o", "--output", required=True, help="texture file to write (.npz)")
    t.add_argument("--apply", metavar="MESH", help="also write the textured target mesh")
    pl = t.add_argument_group("planar mode")
    pl.add_argument("--planar", action="store_true",
                    help="the source is a flat texture in the XY plane; tile it over TARGET")
    pl.add_argument("--scale", type=float, metavar="S",
                    help="surface length of one source unit on the target (required)")
    pl.add_argument("--field", default="up", metavar="up|smooth|FILE.npz",
                    help="direction the texture's x axis follows (default up; a field file "
                    "from 'geotex field' for TARGET's faces)")
    pl.add_argument("--up", default="0,0,1", metavar="X,Y,Z",
                    help="the up direction for --field up (default 0,0,1)")
    pl.add_argument("--refine", choices=("remesh", "subdivide", "none"), default="remesh",
                    help="how TARGET is refined to the texture's resolution (default remesh)")
    pl.add_argument("--seed", type=int, default=0, help="patch seed order (default 0)")
    pl.add_argument("--base-out", metavar="MESH",
                    help="write the refined target the texture lives on (required)")
    t.set_defaults(run=run_transfer)

    d = hs.add_parser("edit", help="set tilt, wrap, wiggle or scale the height",
                      description="Edit a texture; tilt edits need the base mesh.")
    d.add_argument("texture", help="texture file (.npz)")
    how = d.add_mutually_exclusive_group(required=True)
    how.add_argument("--set-tilt", type=float, metavar="DEG", help="lean every element by DEG")
    how.add_argument("--wrap", type=float, metavar="K", help="bend elements: lean = K x height")
    how.add_argument("--wiggle", type=float, metavar="AMP",
                     help="travelling wave of lean, AMP degrees at most; see --phase")
    how.add_argument("--scale-height", type=float, metavar="S", help="multiply heights by S")
    d.add_argument("--direction", metavar="X,Y,Z", help="lean direction (default: as extracted)")
    d.add_argument("--phase", type=float, metavar="P",
                   help="wave phase for --wiggle, radians (default 0); step it for animation "
                   "frames")
    d.add_argument("--base", help="base mesh file (needed by --set-tilt, --wrap, --wiggle; "
                   "checked against the texture with --scale-height)")
    d.add_argument("-o", "--output", required=True, help="texture file to write (.npz)")
    d.set_defaults(run=run_edit)


def _vector(text, option):
    try:
        v = [float(x) for x in text.split(",")]
    except ValueError:
        v = []
    if len(v) != 3:
        raise UsageError(f"{option} {text!r}: give three comma-separated numbers, e.g. 1,0,0")
    return v


def _npz(path, option="-o"):
    if not str(path).lower().endswith(".npz"):
        raise UsageError(f"{path}: texture files are .npz; use a .npz name for {option}")


def _mesh_out(path):
    """Check a mesh output's extension before any work is done."""
    from geotex.io import format_of

    if path is not None:
        format_of(path, writing=True)
    return path


@contextmanager
def _all_or_none():
    """Collect the outputs of one command: if a later one fails, the earlier go too.

    Yields ``done(path)``, to be called after each file is written.  Each file
    is itself written atomically; on an exception the files of this run that
    did not exist before it are removed again, so a failed command leaves no
    new output behind.
    """
    written = []

    def done(path, existed):
        if not existed:
            written.append(Path(path))

    try:
        yield done
    except BaseException:
        for path in written:
            with suppress(OSError):
                path.unlink()
        raise


def run_extract(args) -> int:
    from geotex.heighttilt import extract_texture, save_texture
    from geotex.io import read_mesh, write_mesh

    out = guard_output(args.output, args.textured, args.base)
    _npz(out)
    base_out = (_mesh_out(guard_output(args.base_out, args.textured, args.base))
                if args.base_out else None)
    if args.smooth_steps < 1:
        raise UsageError(f"--smooth-steps {args.smooth_steps}: give at least 1")
    mesh = read_mesh(args.textured)
    base = None
    if args.base:
        b = read_mesh(args.base)
        if b.n_faces != mesh.n_faces or not (b.faces == mesh.faces).all():
            raise UsageError(f"{args.base}: the base must have the same faces as "
                             f"{args.textured} ({b.n_faces} vs {mesh.n_faces} faces)")
        base = b.vertices
    tex, Vs = extract_texture(mesh.vertices, mesh.faces, base=base, steps=args.smooth_steps)
    with _all_or_none() as done:
        if base_out is not None:
            existed = base_out.exists()
            write_mesh(base_out, mesh.with_geometry(Vs, mesh.faces))
            done(base_out, existed)
        save_texture(out, tex)
    h = tex.height
    print(f"{args.textured}: {mesh.n_vertices} vertices, heights {h.min():.4g} .. {h.max():.4g}")
    print(f"wrote {out}" + (f" and {base_out}" if base_out else ""))
    return EXIT_OK


def run_apply(args) -> int:
    from geotex.heighttilt import apply_texture, load_texture, reapplied
    from geotex.io import read_mesh, write_mesh

    out = _mesh_out(guard_output(args.output, args.texture, args.base, args.original))
    tex = load_texture(args.texture)
    base = read_mesh(args.base)
    if args.original:
        original = read_mesh(args.original)
        if original.n_faces != base.n_faces or not (original.faces == base.faces).all():
            raise UsageError(f"{args.original}: the original base must have the same faces "
                             f"as {args.base} ({original.n_faces} vs {base.n_faces} faces)")
        V = reapplied(base.vertices, base.faces, tex, base=original.vertices)
    else:
        V = apply_texture(base.vertices, base.faces, tex)
    write_mesh(out, base.with_geometry(V, base.faces))
    print(f"wrote {out}: {base.n_vertices} vertices, {base.n_faces} faces")
    return EXIT_OK


def run_edit(args) -> int:
    from geotex.heighttilt import load_texture, save_texture, scale_height, set_tilt, wiggle, wrap
    from geotex.heighttilt.reconstruct import check_texture
    from geotex.io import read_mesh

    out = guard_output(args.output, args.texture, args.base)
    _npz(out)
    if args.phase is not None and args.wiggle is None:
        raise UsageError("--phase belongs to --wiggle")
    if args.direction and args.scale_height is not None:
        raise UsageError("--direction belongs to --set-tilt, --wrap and --wiggle, "
                         "not to --scale-height")
    tex = load_texture(args.texture)
    direction = _vector(args.direction, "--direction") if args.direction else None
    if args.scale_height is not None:
        if args.base:
            base = read_mesh(args.base)
            check_texture(base.vertices, base.faces, tex)
        new = scale_height(tex, args.scale_height)
    else:
        if not args.base:
            raise UsageError("--set-tilt, --wrap and --wiggle need --base BASE "
                             "(the base mesh the texture lives on)")
        base = read_mesh(args.base)
        Vs, F = base.vertices, base.faces
        if args.set_tilt is not None:
            new = set_tilt(Vs, F, tex, angle_degrees=args.set_tilt, direction=direction)
        elif args.wrap is not None:
            new = wrap(Vs, F, tex, k=args.wrap, direction=direction)
        else:
            if direction is None:
                raise UsageError("--wiggle needs --direction X,Y,Z (the wave's direction)")
            new = wiggle(Vs, F, tex, amplitude=args.wiggle, phase=args.phase or 0.0,
                         direction=direction)
    save_texture(out, new)
    print(f"wrote {out}")
    return EXIT_OK


#: --map auto picks closest points when the target lies this close to the source base
#: (fraction of the source base's bounding-box diagonal), else the sphere map.
AUTO_CLOSEST_DISTANCE = 0.02


def _landmarks(path):
    import json

    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except FileNotFoundError:
        raise UsageError(f"--landmarks {path}: no such file") from None
    except (OSError, ValueError) as exc:
        raise UsageError(f"--landmarks {path}: not readable JSON ({exc})") from None
    from geotex.heighttilt.transfer import check_landmarks
    from geotex.errors import InputError

    try:
        check_landmarks(data)
    except InputError as exc:
        raise UsageError(f"--landmarks {path}: {exc}") from None
    return data


def _auto_map(src, dst) -> str:
    import igl
    import numpy as np

    diag = float(np.linalg.norm(np.ptp(src.vertices, axis=0)))
    d2, _, _ = igl.point_mesh_squared_distance(dst.vertices, src.vertices, src.faces)
    return "closest" if float(np.sqrt(np.max(d2))) <= AUTO_CLOSEST_DISTANCE * diag else "sphere"


def run_transfer(args) -> int:
    if args.planar:
        if args.map != "auto" or args.landmarks:
            raise UsageError("--map and --landmarks do not apply to --planar")
        return _run_planar(args)
    if args.scale is not None or args.base_out:
        raise UsageError("--scale and --base-out belong to the planar mode; add --planar")
    if args.landmarks and args.map == "closest":
        raise UsageError("--landmarks belongs to --map sphere")
    from geotex.heighttilt import (apply_texture, closest_point_correspondence, load_texture,
                                   save_texture, transfer_texture)
    from geotex.heighttilt.transfer import transfer_between_shapes
    from geotex.io import read_mesh, write_mesh

    inputs = (args.texture, args.source_base, args.target) + ((args.landmarks,)
                                                              if args.landmarks else ())
    out = guard_output(args.output, *inputs)
    _npz(out)
    applied = _mesh_out(guard_output(args.apply, *inputs)) if args.apply else None
    landmarks = _landmarks(args.landmarks) if args.landmarks else None
    tex = load_texture(args.texture)
    src = read_mesh(args.source_base)
    dst = read_mesh(args.target)
    how = args.map
    if how == "auto":
        how = "sphere" if landmarks is not None else _auto_map(src, dst)
    if how == "closest":
        corr = closest_point_correspondence(dst.vertices, src.vertices, src.faces)
        new = transfer_texture(src.vertices, src.faces, tex, dst.vertices, dst.faces,
                               correspondence=corr, samples=args.samples)
        print("map: closest points")
    else:
        from geotex.errors import InputError

        try:
            new, report = transfer_between_shapes(src.vertices, src.faces, tex, dst.vertices,
                                                  dst.faces, landmarks=landmarks,
                                                  samples=args.samples)
        except InputError as exc:
            msg = str(exc)
            for name, flag, path in (("V_dst ", "--target-base", args.target),
                                     ("Vs_src ", "--source-base", args.source_base)):
                if msg.startswith(name):
                    raise UsageError(f"{flag} {path}: {msg[len(name):]} (--map sphere)") from None
            raise
        print("\n".join(report.lines()))
    with _all_or_none() as done:
        if applied is not None:
            V = apply_texture(dst.vertices, dst.faces, new)
            existed = applied.exists()
            write_mesh(applied, dst.with_geometry(V, dst.faces))
            done(applied, existed)
        save_texture(out, new)
    print(f"transferred onto {args.target} ({dst.n_vertices} vertices); wrote {out}"
          + (f" and {applied}" if applied else ""))
    return EXIT_OK


def _run_planar(args) -> int:
    from geotex.heighttilt import apply_texture, load_texture, save_texture
    from geotex.heighttilt.planar import transfer_planar
    from geotex.io import read_mesh, write_mesh
    from geotex.progress import stage_bar

    if args.scale is None:
        raise UsageError("--planar needs --scale S (surface length of one source unit)")
    if not args.base_out:
        raise UsageError("--planar needs --base-out MESH: the texture lives on the refined "
                         "target, which is written there")
    inputs = (args.texture, args.source_base, args.target)
    field = args.field
    if field not in ("up", "smooth"):
        if not str(field).lower().endswith(".npz"):
            raise UsageError(f"--field {field!r}: give up, smooth or a field file (.npz)")
        inputs += (field,)
    out = guard_output(args.output, *inputs)
    _npz(out)
    base_out = _mesh_out(guard_output(args.base_out, *inputs))
    applied = _mesh_out(guard_output(args.apply, *inputs)) if args.apply else None
    outs = [str(p.resolve()) for p in (out, base_out, applied) if p is not None]
    if len(set(outs)) != len(outs):
        raise UsageError("-o, --base-out and --apply must be different files")
    up = _vector(args.up, "--up")
    tex = load_texture(args.texture)
    src = read_mesh(args.source_base)
    dst = read_mesh(args.target)
    if field not in ("up", "smooth"):
        from geotex.fields import load_direction_field
        field = load_direction_field(field).field
    from geotex.errors import InputError

    try:
        with stage_bar(6, "planar transfer") as bar:
            res = transfer_planar(src.vertices, src.faces, tex, dst.vertices, dst.faces,
                                  scale=args.scale, field=field, up=up, refine=args.refine,
                                  samples=args.samples, seed=args.seed, progress=bar)
    except InputError as exc:
        if str(exc).endswith("try refining by subdivision instead"):
            raise UsageError(f"{exc} (--refine subdivide)") from None
        raise
    with _all_or_none() as done:
        existed = base_out.exists()
        write_mesh(base_out, dst.with_geometry(res.vertices, res.faces))
        done(base_out, existed)
        if applied is not None:
            V = apply_texture(res.vertices, res.faces, res.texture)
            existed = applied.exists()
            write_mesh(applied, dst.with_geometry(V, res.faces))
            done(applied, existed)
        save_texture(out, res.texture)
    print(f"{args.target}: refined to {res.vertices.shape[0]} vertices, {res.faces.shape[0]} "
          f"faces; {res.n_patches} patches")
    print(f"wrote {out} and {base_out}" + (f" and {applied}" if applied else ""))
    return EXIT_OK
