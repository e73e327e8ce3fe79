"""``geotex tile-image BASE --image IMG --param P.npz -o OUT.glb|.obj``: a tileable image over a PGP.

With ``--displace DEPTH -o OUT.stl|.3mf`` the image is a height map instead
and the relief goes through the shared displacement path
(:func:`geotex.displace.displace_file` with the ``uv`` mapping on the PGP's
coordinates), written only when printable as stored.
"""

from __future__ import annotations

from geotex.cli._common import EXIT_OK, UsageError, guard_output
from geotex.cli.relief import add_relief_arguments, check_relief_output, write_relief

HELP = "lay a tileable image over a mesh through its periodic parameterization (geotex pgp)"
TEXTURED = (".glb", ".obj")


def register(sub):
    p = sub.add_parser("tile-image", help=HELP, description=HELP + ". The per-corner tile "
                       "coordinates of the PGP file become the texture coordinates (one "
                       "image period per tile, repeated): no atlas, no seams except at the "
                       "field's singularities. Writes OUT.glb, or OUT.obj + OUT.mtl + OUT.png; with "
                       "--displace, a printable relief OUT.stl or OUT.3mf.")
    p.add_argument("base", metavar="BASE", help="the mesh the PGP file was computed on")
    p.add_argument("--image", required=True, metavar="IMG",
                   help="tileable image (PNG, JPEG): one period per tile")
    p.add_argument("--param", required=True, metavar="P.npz",
                   help="periodic parameterization written by 'geotex pgp' for BASE")
    p.add_argument("--make-tileable", type=int, default=None, metavar="PX",
                   help="the image is not periodic: make a PX x PX periodic tile from its "
                        "central square first (graph-cut wrap, as for material-space tiles)")
    add_relief_arguments(p, what="the image as a height map through the PGP")
    p.add_argument("-o", "--output", required=True,
                   help="OUT.glb or OUT.obj (textured), OUT.stl or OUT.3mf (with --displace)")
    p.set_defaults(run=run)


#: Largest tile --make-tileable makes (the graph-cut wrap grows faster than the area).
MAX_TILEABLE_PX = 1024


def run(args) -> int:
    from geotex.errors import InputError
    from geotex.image.patches import load_image
    from geotex.image.tiled import tiled_texture_mesh
    from geotex.io import read_mesh, write_mesh
    from geotex.param.pgp_store import load_parameterization

    if args.make_tileable is not None and args.make_tileable > MAX_TILEABLE_PX:
        raise UsageError(f"--make-tileable {args.make_tileable}: at most {MAX_TILEABLE_PX} "
                         "texels a side (the graph cut would take minutes)")
    out = guard_output(args.output, args.base, args.image, args.param)
    suffix = out.suffix.lower()
    if args.displace is None and suffix not in TEXTURED:
        raise UsageError(f"{out}: a tiled image is written as .glb or .obj (+ .mtl + .png); "
                         f"got '{out.suffix}' (a relief needs --displace MM)")
    check_relief_output(args, out)
    mesh = read_mesh(args.base)
    try:
        pgp = load_parameterization(args.param)
    except InputError as exc:
        raise UsageError(f"--param {exc}") from None
    if pgp.coords.shape[0] != mesh.n_faces:
        raise UsageError(f"--param {args.param}: made for a mesh of {pgp.coords.shape[0]} faces, "
                         f"but {args.base} has {mesh.n_faces}; run 'geotex pgp' on this mesh")
    try:
        image = load_image(args.image)
    except InputError as exc:
        raise UsageError(f"--image {exc}") from None
    import numpy as np

    if image.shape[2] == 4 and (image[:, :, 3] < 128).any():
        from geotex.image.holes import transparent_filled

        # a texture with holes would show them on every tile: filled from the image
        filled = transparent_filled(image[:, :, :3], image[:, :, 3] / 255.0)
        image = np.clip(np.rint(filled), 0, 255).astype(np.uint8)
        print(f"--image {args.image}: transparent texels filled from the opaque parts")
    if args.make_tileable is not None:
        from geotex.image.material.tileable import tileable_image

        try:
            tile = tileable_image(image, size=args.make_tileable)
        except InputError as exc:
            raise UsageError(f"--make-tileable {args.make_tileable}: {exc}") from None
        image = np.clip(np.rint(tile.colors * 255.0), 0, 255).astype(np.uint8)
    if args.displace is not None:
        return write_relief(args, args.base, image, out, pgp.coords)
    textured = tiled_texture_mesh(mesh.vertices, mesh.faces, pgp.coords, image,
                                  name=mesh.name or "geotex")
    write_mesh(out, textured)
    print(f"wrote {out}: {mesh.n_faces} faces, {int(pgp.singular.sum())} singular, "
          f"image {image.shape[1]}x{image.shape[0]} per tile")
    return EXIT_OK

