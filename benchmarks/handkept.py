"""Writing a results file while keeping the sections someone wrote by hand.

Generated tables go at the top of a ``benchmarks/results/*.md`` file; the
readings, comparisons and notes below them are headed ``## ... (written by
hand ...)``. A generator re-run must replace its tables and keep those.
"""

from __future__ import annotations

import re
from pathlib import Path

__all__ = ["write_keeping_hand_sections"]

_HAND = re.compile(r"^## [^\n]*\(written by hand", flags=re.M)


def write_keeping_hand_sections(path, text: str) -> None:
    """Write ``text`` to ``path``; the old file's part from its first section headed
    ``## ... (written by hand`` on is kept below it."""
    path = Path(path)
    kept = ""
    if path.exists():
        old = path.read_text()
        hand = _HAND.search(old)
        kept = old[hand.start():] if hand else ""
    text = text if text.endswith("\n") else text + "\n"
    path.write_text(text + ("\n" + kept if kept else ""))
