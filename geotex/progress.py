"""Progress reporting: library functions take an optional ``progress`` callback.

Library calls are quiet by default.  A long operation accepts
``progress=callable`` and calls it with a short stage name as each stage
starts; the command line passes a tqdm bar from :func:`stage_bar`.
"""

from __future__ import annotations

import sys
import threading
from contextlib import contextmanager
from typing import Callable, Iterator

from tqdm import tqdm

__all__ = ["ProgressCallback", "stage_bar", "report"]

ProgressCallback = Callable[[str], None]


def report(progress: ProgressCallback | None, stage: str) -> None:
    """Call ``progress(stage)`` when a callback is given."""
    if progress is not None:
        progress(stage)


@contextmanager
def stage_bar(total: int, desc: str, *, enabled: bool | None = None
              ) -> Iterator[ProgressCallback]:
    """Yield a callback that advances a tqdm bar on stderr by one stage per call.

    The bar is redrawn every half second, so its elapsed time moves during a
    long stage too.

    Parameters
    ----------
    total : int
        Number of stages.
    desc : str
        Bar label.
    enabled : bool, optional
        Default: only when stderr is a terminal.
    """
    if enabled is None:
        enabled = sys.stderr.isatty()
    bar = tqdm(total=total, desc=desc, unit="stage", leave=False, disable=not enabled,
               file=sys.stderr)
    started = [False]

    def advance(stage: str) -> None:
        if started[0]:
            bar.update()
        started[0] = True
        bar.set_postfix_str(stage, refresh=True)

    stop = threading.Event()

    def tick() -> None:
        while not stop.wait(0.5):
            bar.refresh()

    ticker = threading.Thread(target=tick, daemon=True) if enabled else None
    if ticker is not None:
        ticker.start()
    try:
        yield advance
    finally:
        stop.set()
        if ticker is not None:
            ticker.join()
        bar.close()
