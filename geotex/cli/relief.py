"""The ``--displace MM`` option that several commands share: an image read through a
command's own texture coordinates becomes a printable relief (the shared relief path,
:func:`geotex.displace.displace_file` with the ``uv`` mapping)."""

from __future__ import annotations

import math
import sys

from geotex.cli._common import EXIT_NOT_PRINTABLE, EXIT_OK, UsageError, flag_error

PRINTS = (".stl", ".3mf")


def add_relief_arguments(p, *, what: str, size: bool = True) -> None:
    """Add ``--displace MM`` (with ``--faces N`` and, optionally, ``--size-mm L``)."""
    p.add_argument("--displace", type=float, default=None, metavar="MM",
                   help=f"write a printable relief instead: {what} (white high) raised by up "
                        "to MM along the surface (OUT.stl or OUT.3mf)")
    if size:
        p.add_argument("--size-mm", type=float, default=None, metavar="L",
                       help="with --displace: scale the part so its largest extent is L mm")
    p.add_argument("--faces", type=int, default=1_000_000, metavar="N",
                   help="with --displace: about N refined faces (default 1000000)")


def check_relief_output(args, out) -> None:
    """Refuse a relief to a textured format, a texture to a print format, a bad depth."""
    if args.displace is None:
        return
    if out.suffix.lower() not in PRINTS:
        raise UsageError(f"{out}: --displace writes a relief as .stl or .3mf; got "
                         f"'{out.suffix}'")
    if not (math.isfinite(args.displace) and args.displace > 0):
        raise UsageError(f"--displace {args.displace!r}: give a positive depth in mm")


def write_relief(args, base, image, out, uv) -> int:
    """Displace ``base`` by ``image`` read at per-corner ``uv``; write it only if printable.

    Returns the exit status (``EXIT_NOT_PRINTABLE`` with one line on stderr when
    the result is not printable as stored).
    """
    from geotex.displace import DISPLACE_STAGES, displace_file
    from geotex.errors import InputError, NotPrintableError
    from geotex.progress import stage_bar

    try:
        with stage_bar(len(DISPLACE_STAGES), "relief") as bar:
            res = displace_file(base, image, out, depth=args.displace, mapping="uv", uv=uv,
                                target_faces=args.faces,
                                size_mm=getattr(args, "size_mm", None), progress=bar)
    except NotPrintableError as exc:
        print(f"geotex: error: {out}: not written, not printable as stored "
              f"({'; '.join(exc.report.reasons)})", file=sys.stderr)
        return EXIT_NOT_PRINTABLE
    except InputError as exc:
        raise flag_error(exc, {"depth": "--displace", "target_faces": "--faces",
                               "size_mm": "--size-mm"}) from None
    print(f"wrote {out}: relief {args.displace:g} mm, {res.faces.shape[0]} faces "
          "(printable as written)")
    return EXIT_OK
