"""Summary of a batch: one row per part, written as ``summary.csv`` and ``summary.json``.

Row fields (:data:`FIELDS`):

``part``, ``job``, ``input``, ``output``
    Part name, job, input, output file name (empty when the job writes none).
``status``
    ``ok``; ``failed`` (``reason`` says why, in one line); ``skipped``
    (``--resume``: it passed in the previous run and its file is unchanged);
    ``pending`` (not finished when the summary was written: an interrupted run).
``reason``
    One line: the :class:`~geotex.errors.GeotexError` message of a failed part.
``faces``, ``tile_size``, ``coverage``
    Faces of the output; tile side chosen (mm); share of the base within a
    tile of the polycube (``texture``, ``map``) or covered by pastes (``lapped``).
``seconds``, ``cpu_seconds``
    Wall time of the part on its worker, and the CPU time its process spent
    meanwhile (all threads; less than ``seconds`` when the machine is busy).
``printable``
    The verdict on the written file: :func:`geotex.printing.export_printable`
    judges exactly the arrays the file reads back as (it reads the written
    file back and compares it bit for bit before renaming it into place).
``bytes``, ``mtime_ns``
    Size and modification time of the output (or of the input for a job
    without output); ``--resume`` compares them.
``worker``, ``worker_peak_mb``
    Which worker ran the part (``host:pid``) and that process's peak resident
    memory when the part ended (MB).
``options``
    The part's options (JSON), compared by ``--resume``.
"""

from __future__ import annotations

import csv
import io
import json
from pathlib import Path

__all__ = ["FIELDS", "write_summary", "read_summary", "SUMMARY_CSV", "SUMMARY_JSON"]

FIELDS = ("part", "job", "input", "output", "status", "reason", "faces", "tile_size",
          "coverage", "seconds", "cpu_seconds", "printable", "bytes", "mtime_ns", "worker", "worker_peak_mb",
          "options")
SUMMARY_CSV = "summary.csv"
SUMMARY_JSON = "summary.json"


def _cell(value) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, dict):
        return json.dumps(value, sort_keys=True)
    return str(value)


def write_summary(outdir, rows: list[dict], *, meta: dict | None = None) -> tuple[Path, Path]:
    """Write ``OUTDIR/summary.csv`` and ``OUTDIR/summary.json`` atomically.

    Parameters
    ----------
    outdir : str or os.PathLike
    rows : list of dict
        Summary rows (:data:`FIELDS`).
    meta : dict, optional
        Stored in the JSON next to the rows (job counts, workers, wall time).

    Returns
    -------
    tuple of 2 pathlib.Path
        The CSV and JSON paths.
    """
    # lazy: `geotex --help` imports geotex.batch; geotex.io would add ~25-50 ms to it
    from geotex.io.atomic import atomic_group

    outdir = Path(outdir)
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(FIELDS)
    for row in rows:
        writer.writerow([_cell(row.get(f)) for f in FIELDS])
    doc = {"fields": list(FIELDS), "rows": [{f: row.get(f) for f in FIELDS} for row in rows]}
    if meta:
        doc["meta"] = meta
    paths = outdir / SUMMARY_CSV, outdir / SUMMARY_JSON
    with atomic_group() as group:
        group.open(paths[0], "w").write(buf.getvalue())
        group.open(paths[1], "w").write(json.dumps(doc, indent=1, sort_keys=False) + "\n")
    return paths


def read_summary(outdir) -> list[dict]:
    """Rows of ``OUTDIR/summary.json`` (empty when there is none or it is unreadable)."""
    path = Path(outdir) / SUMMARY_JSON
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
        rows = doc["rows"]
    except (OSError, ValueError, KeyError, TypeError):
        return []
    return [r for r in rows if isinstance(r, dict) and isinstance(r.get("part"), str)]
