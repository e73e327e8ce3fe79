"""``geotex batch MANIFEST.csv|DIR -o OUTDIR``: many parts on Dask, locally or on a cluster."""

from __future__ import annotations

import sys
from pathlib import Path

from geotex.cli._common import EXIT_NOT_PRINTABLE, EXIT_OK, UsageError

HELP = "run a job over a folder or manifest of parts on Dask (local processes or a cluster)"


def register(sub):
    from geotex.batch.jobs import JOBS

    p = sub.add_parser("batch", help=HELP, description=HELP + ". One task per part; a part "
                       "that fails is recorded with its reason and the batch goes on. Writes "
                       "one output per part and OUTDIR/summary.csv and summary.json. Exit "
                       "status: 0 every part passed (or was skipped by --resume), 1 at least "
                       "one part failed (see the summary), 2 bad usage or an unreadable "
                       "manifest.")
    p.add_argument("parts", metavar="MANIFEST.csv|DIR",
                   help="CSV manifest (columns input, name, job, tiles, size_mm, tile_size, "
                   "height, seed, image; only input is required) or a folder of mesh files "
                   "(shell .npz files for --job map)")
    p.add_argument("-o", "--output", required=True, metavar="OUTDIR",
                   help="output folder (created if missing)")
    p.add_argument("--job", choices=tuple(JOBS), default="texture",
                   help="job of the parts that do not name one (default texture)")
    p.add_argument("--tiles", default=None, metavar="SET",
                   help="tile set of the parts that do not name one: catalog name or .npz")
    p.add_argument("--size-mm", type=float, default=None,
                   help="print size (largest extent, mm) of the parts that do not give one")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the parts that do not give one (default 0)")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="local Dask worker processes (default: the cores available; 0 runs "
                   "the parts one after another in this process)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="connect to a running Dask scheduler (tcp://host:8786) instead of "
                   "starting local workers")
    p.add_argument("--resume", action="store_true",
                   help="skip parts that passed in the previous run into OUTDIR (same options, "
                   "output file unchanged)")
    p.set_defaults(run=run)


def _check_args(args) -> Path:
    from geotex.errors import GeotexError
    from geotex.tiles.catalog import tileset_path

    if args.workers is not None and args.workers < 0:
        raise UsageError(f"--workers {args.workers}: give a number of workers >= 0")
    if args.scheduler is not None and args.workers is not None:
        raise UsageError("--workers and --scheduler exclude each other: the scheduler's "
                         "cluster has its own workers")
    if args.scheduler is not None and "://" not in args.scheduler:
        raise UsageError(f"--scheduler {args.scheduler}: give an address such as "
                         "tcp://host:8786")
    if args.seed < 0:
        raise UsageError(f"--seed {args.seed}: give a non-negative integer")
    if args.size_mm is not None and not (0 < args.size_mm <= 10000):
        raise UsageError(f"--size-mm {args.size_mm}: give a size in (0, 10000] mm")
    if args.tiles is not None:
        try:
            tileset_path(args.tiles)
        except GeotexError as exc:
            raise UsageError(f"--tiles {args.tiles}: {exc}") from None
    src = Path(args.parts)
    if not src.exists():
        raise UsageError(f"{src}: no such manifest file or folder")
    out = Path(args.output)
    if out.exists() and not out.is_dir():
        raise UsageError(f"{out}: -o must be a folder, and this is a file")
    if not out.parent.exists():
        raise UsageError(f"{out}: folder {out.parent} does not exist")
    if src.is_dir() and out.resolve() == src.resolve():
        raise UsageError(f"{out}: the output folder is the input folder; choose another -o")
    return out


def run(args) -> int:
    from tqdm import tqdm

    from geotex.batch import read_parts, run as run_batch

    out = _check_args(args)
    parts = read_parts(args.parts, job=args.job, tiles=args.tiles, seed=args.seed,
                       size_mm=args.size_mm)
    bar = tqdm(total=len(parts), desc=f"batch {args.job}", unit="part", file=sys.stderr,
               disable=not sys.stderr.isatty())
    failed_now = []

    def progress(row, done, total):
        bar.update(1)
        if row["status"] == "failed":
            failed_now.append(row)
        bar.set_postfix_str(f"{len(failed_now)} failed", refresh=True)

    try:
        rows = run_batch(parts, outdir=out, workers=args.workers, scheduler=args.scheduler,
                         resume=args.resume, progress=progress)
    finally:
        bar.close()
    counts = {s: sum(r["status"] == s for r in rows) for s in ("ok", "failed", "skipped")}
    for r in rows:
        if r["status"] == "failed":
            print(f"{r['part']}: failed: {r['reason']}", file=sys.stderr)
    seconds = sum(r["seconds"] or 0.0 for r in rows if r["status"] != "skipped")
    print(f"{len(rows)} parts: {counts['ok']} ok, {counts['failed']} failed, "
          f"{counts['skipped']} skipped (passed before); {seconds:.1f} s of work")
    print(f"wrote {out / 'summary.csv'} and {out / 'summary.json'}")
    return EXIT_NOT_PRINTABLE if counts["failed"] else EXIT_OK
