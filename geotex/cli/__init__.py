"""The ``geotex`` command: one subcommand per job, one-line errors, exit codes.

Exit status:

* 0 success (the mesh or the result is printable);
* 1 a readable mesh that is not printable, or a result refused as not
  printable (``geotex repair`` also when the repair changed the number of
  shells or lost volume, unless ``--force``);
* 2 bad usage, or an input that cannot be used: missing, unreadable,
  malformed, truncated, hostile (references outside its folder, zip bombs,
  absurd counts, see :mod:`geotex.io.limits`) or too large for the memory
  available.  stderr holds exactly one line ``geotex: error: ...`` naming the
  file or the flag and what is wrong;
* 3 an internal error only: a bug in geotex, whatever the input (please
  report it; set ``GEOTEX_DEBUG=1`` for the traceback).
"""

from __future__ import annotations

import gc
import os
import sys

from geotex import __version__
from geotex.cli import (batch, check, convert, demo, displace, exemplar, field, heighttilt,
                        hpm, lapped, mapping, material, pgp, quilt, render, repair, shell,
                        tile_image, tiles, view)
from geotex.cli._common import EXIT_INTERNAL, EXIT_USAGE, PRELOADS, Parser, fail
from geotex.errors import GeotexError
from geotex.jit import on_first_compile
from geotex.malloc import keep_freed_memory

COMMANDS = (demo, mapping, check, repair, render, convert, field, pgp, tile_image, heighttilt,
            exemplar, quilt, tiles, shell, lapped, displace, hpm, material, view, batch)


def build_parser() -> Parser:
    """Return the argument parser of the ``geotex`` command."""
    parser = Parser(prog="geotex", description="Geometric texture on triangle meshes, "
                    "made printable.")
    parser.add_argument("--version", action="version", version=f"geotex {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for module in COMMANDS:
        module.register(sub)
    return parser


def _compiling_note(name: str) -> None:
    """Say on the terminal why this run is slow: numba compiles geotex's loops (first run only)."""
    from tqdm import tqdm

    tqdm.write("geotex: first run on this machine: compiling geotex's loops once "
               "(up to a minute or two); later runs load them", file=sys.stderr)


def main(argv=None) -> int:
    """Run the command line; returns the exit status (also used by the script).

    With ``argv`` None (the process's own command line: ``python -m geotex``
    and the ``geotex`` script), the process exits next, so its objects are
    frozen out of the garbage collector before it returns
    (:func:`gc.freeze`): the collections of the interpreter's shutdown
    otherwise walk every object numba and the job left, 0.4-0.5 s of CPU
    after a ``geotex map`` at ~370k faces. A caller passing ``argv`` goes on
    living and keeps its collector as it was.
    """
    keep_freed_memory()
    if sys.stderr.isatty():
        on_first_compile(_compiling_note)
    try:
        args = build_parser().parse_args(argv)
        if not getattr(args, "run", None):
            return fail("no command given (see 'geotex --help')")
        return args.run(args)
    except GeotexError as exc:
        return fail(str(exc), EXIT_USAGE)
    except KeyboardInterrupt:
        print("geotex: interrupted", file=sys.stderr)
        return 130
    except MemoryError:   # inputs are bounded (geotex.io.limits): this one is just large
        if os.environ.get("GEOTEX_DEBUG"):
            raise
        return fail("out of memory: the input is too large for the memory available; "
                    "try a smaller mesh", EXIT_USAGE)
    except Exception as exc:  # an unexpected failure is a bug: one line unless debugging
        if os.environ.get("GEOTEX_DEBUG"):
            raise
        return fail(f"internal error: {type(exc).__name__}: {exc} "
                    "(set GEOTEX_DEBUG=1 for the traceback)", EXIT_INTERNAL)
    finally:
        while PRELOADS:               # never exit while a thread is inside numba / LLVM
            PRELOADS.pop().join()
        if argv is None:
            gc.freeze()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
