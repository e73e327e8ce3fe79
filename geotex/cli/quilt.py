"""``geotex quilt``: synthesize a larger geometric texture from an exemplar (mesh quilting)."""

from __future__ import annotations

import re
import sys
from contextlib import contextmanager
from pathlib import Path

from geotex.cli._common import EXIT_OK, UsageError, guard_output

HELP = "synthesize a larger planar geometric texture from an exemplar (mesh quilting)"


def register(sub):
    p = sub.add_parser("quilt", help=HELP, description=HELP.capitalize() + ". EXEMPLAR is "
                       "an exemplar kind (see 'geotex exemplar --list'), an exemplar .npz, or "
                       "a mesh file whose connected components are the elements.")
    p.add_argument("exemplar", help="exemplar kind, exemplar .npz, or mesh file")
    p.add_argument("--size", type=float, nargs=2, metavar=("W", "H"), required=True,
                   help="size of the output texture, [0, W] x [0, H]")
    p.add_argument("-o", "--output", required=True, help="mesh file to write")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--exemplar-size", type=float, nargs=2, metavar=("LX", "LY"),
                   default=(2.0, 2.0),
                   help="size of a procedural exemplar given by kind (default 2 2)")
    p.add_argument("--cell", type=float, help="grid cell (default: about one element pitch)")
    p.add_argument("--boundary", choices=("drop", "clip"), default="drop",
                   help="elements crossing the border: drop them (default, elements stay "
                   "whole) or clip them to the border (flat cut, better coverage)")
    p.add_argument("--report", metavar="R.json", help="also write the quality report (JSON)")
    p.set_defaults(run=run)


def _load(spec: str, size, seed):
    from geotex.exemplars import EXEMPLAR_KINDS, exemplar, load_exemplar

    if spec in EXEMPLAR_KINDS and not Path(spec).exists():
        return exemplar(spec, size=tuple(size), seed=seed), None
    path = Path(spec)
    if not path.exists():
        raise UsageError(f"{spec}: no such file, and not an exemplar kind "
                         f"({', '.join(EXEMPLAR_KINDS)})")
    return load_exemplar(path), path


_CELLS = re.compile(r"(\d+)/(\d+) cells")


@contextmanager
def cell_bar(total: int, desc: str, *, enabled: bool | None = None):
    """A tqdm bar on stderr (only on a terminal) counting the filled grid cells.

    Yields the ``progress`` callback for :func:`geotex.quilting.quilt_texture`,
    which reports ``"placement K: FILLED/TOTAL cells"`` before every
    placement; the bar shows FILLED of TOTAL and the placement number, and
    is completed when the loop ends.
    """
    from tqdm import tqdm

    if enabled is None:
        enabled = sys.stderr.isatty()
    bar = tqdm(total=total, desc=desc, unit="cell", leave=False, disable=not enabled,
               file=sys.stderr)

    def advance(stage: str) -> None:
        m = _CELLS.search(stage)
        if m:
            done, bar.total = int(m.group(1)), int(m.group(2))
            bar.update(done - bar.n)
        bar.set_postfix_str(stage.split(":")[0], refresh=True)

    try:
        yield advance
        bar.update(bar.total - bar.n)
    finally:
        bar.close()


def run(args) -> int:
    from geotex.io import format_of, write_mesh
    from geotex.io.atomic import atomic_output
    from geotex.mesh.record import Mesh
    from geotex.quilting import default_cell, quilt_texture, split_elements

    W, H = args.size
    if not (W > 0 and H > 0):
        raise UsageError(f"--size {W:g} {H:g}: give two positive numbers")
    if min(args.exemplar_size) <= 0:
        raise UsageError("--exemplar-size: give two positive numbers")
    if args.cell is not None and not args.cell > 0:
        raise UsageError(f"--cell {args.cell:g}: give a positive number")
    source = Path(args.exemplar) if Path(args.exemplar).exists() else None
    out = guard_output(args.output, source)
    format_of(out, writing=True)           # an unsupported extension fails before the work
    report_path = guard_output(args.report, source) if args.report else None
    if report_path is not None and report_path.resolve() == out.resolve():
        raise UsageError(f"{report_path}: the report and the mesh need different files")
    ex, _ = _load(args.exemplar, args.exemplar_size, args.seed)
    cell = args.cell or default_cell(split_elements(ex.vertices, ex.faces), ex.size,
                                     getattr(ex, "params", None), getattr(ex, "period", None))
    cx, cy = (cell, cell) if isinstance(cell, float) else cell
    cells = max(1, round(W / cx)) * max(1, round(H / cy))
    with cell_bar(cells, f"quilt {ex.name}") as bar:
        result = quilt_texture(ex, out_size=(W, H), cell=cell, seed=args.seed,
                               boundary=args.boundary, progress=bar)
    write_mesh(out, Mesh(result.vertices, result.faces, name=f"{ex.name}_quilted"))
    if report_path is not None:
        with atomic_output(report_path, "w") as fh:
            fh.write(result.report.to_json(indent=2))
    print(f"wrote {out}: {result.report.summary()}")
    if report_path is not None:
        print(f"wrote {report_path}")
    return EXIT_OK
