"""``geotex exemplar``: build a procedural exemplar geometric texture and write it."""

from __future__ import annotations

from geotex.cli._common import EXIT_OK, UsageError, guard_output

HELP = "build a procedural exemplar geometric texture (studs, scales, knurl, ...)"


def register(sub):
    p = sub.add_parser("exemplar", help=HELP, description=HELP.capitalize() + ". Writes a "
                       ".npz (lossless: geometry + recipe) or any mesh format (geometry).")
    p.add_argument("name", nargs="?", help="exemplar kind (see --list)")
    p.add_argument("--list", action="store_true", help="list the kinds and their parameters")
    p.add_argument("-o", "--output", help="file to write (.npz, .stl, .obj, .ply, .off, "
                   ".3mf, .glb)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--size", type=float, nargs=2, metavar=("LX", "LY"), default=(4.0, 4.0),
                   help="patch size in tile units (default 4 4)")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                   help="kind parameter, repeatable (e.g. --param pitch=0.4)")
    p.set_defaults(run=run)


def _params(name, items):
    from geotex.exemplars import kind_parameters
    from geotex.exemplars.params import parse_value

    specs = {s.name: s for s in kind_parameters(name)}
    out = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise UsageError(f"--param {item!r}: write KEY=VALUE, e.g. --param pitch=0.4")
        if key not in specs:
            raise UsageError(f"--param {key}: exemplar {name!r} has no parameter {key!r}; "
                             f"valid parameters: {', '.join(specs)}")
        out[key] = parse_value(specs[key], text.strip())
    return out


def _listing() -> str:
    from geotex.exemplars import EXEMPLAR_KINDS, describe, kind_parameters

    width = max(len(n) for n in EXEMPLAR_KINDS)
    lines = []
    for name in EXEMPLAR_KINDS:
        lines.append(f"{name:<{width}}  {describe(name)}")
        lines.append(" " * (width + 2) + "params: "
                     + ", ".join(s.describe() for s in kind_parameters(name)))
    return "\n".join(lines)


def run(args) -> int:
    if args.list:
        print(_listing())
        return EXIT_OK
    if not args.name:
        raise UsageError("give an exemplar NAME and -o FILE, or --list")
    if not args.output:
        raise UsageError("-o FILE is required (the exemplar to write)")
    from geotex.exemplars import exemplar, save_exemplar
    from geotex.io import WRITE_FORMATS
    from geotex.progress import stage_bar

    out = guard_output(args.output)
    suffix = out.suffix.lower()
    if suffix != ".npz" and "." + (suffix[1:] or "?") not in WRITE_FORMATS:
        raise UsageError(f"{out}: unsupported extension {suffix or '(none)'!r}; use .npz "
                         f"(keeps the recipe) or one of {', '.join(WRITE_FORMATS)}")
    params = _params(args.name, args.param)
    with stage_bar(2, f"exemplar {args.name}") as bar:
        bar("build")
        ex = exemplar(args.name, size=tuple(args.size), seed=args.seed, **params)
        bar("write")
        save_exemplar(out, ex)
    print(f"wrote {out}: {ex.name}, {ex.n_elements} elements, {ex.faces.shape[0]} faces, "
          f"size {ex.size[0]:g} x {ex.size[1]:g}, height {ex.height:.4g}, "
          f"depth {ex.depth:.4g}" + ("" if out.suffix.lower() == ".npz" else
                                     " (mesh file: recipe not kept; use .npz to keep it)"))
    return EXIT_OK
