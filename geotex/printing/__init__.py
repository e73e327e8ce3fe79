"""Print export: write a solid only when the file, as written, is printable.

The verdict is computed on the coordinates the format stores
(:mod:`geotex.printing.stored`: float32 for STL), and the written file is
read back and compared with the judged arrays before it takes its final name.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from geotex.check.report import CheckReport
from geotex.errors import GeotexError, InputError, NotPrintableError
from geotex.io import read_mesh, write_mesh
from geotex.mesh.arrays import as_mesh_arrays, mesh_digest
from geotex.mesh.record import Mesh
from geotex.printing.stored import (StoredSolid, printable_stored_solid, stored_form,
                                    stored_precision)

__all__ = ["export_printable", "PRINT_FORMATS", "printable_stored_solid", "stored_form",
           "stored_precision", "StoredSolid", "written_form"]

#: Extensions accepted by :func:`export_printable`.
PRINT_FORMATS = (".stl", ".3mf", ".obj", ".ply", ".off")


def written_form(path) -> tuple[np.ndarray, np.ndarray]:
    """Read a print file back in the canonical stored form (equal corners welded).

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    """
    mesh = read_mesh(path)
    return stored_form(mesh.vertices, mesh.faces, precision=np.float64)


def _same(A, B) -> bool:
    return A[0].shape == B[0].shape and np.array_equal(A[0], B[0]) and np.array_equal(A[1], B[1])


def _verified_write(path: Path, V, F, name: str) -> bool:
    """Write, read the file back, and give it its final name only if it matches.

    The file is read back as it is; only when that differs from ``(V, F)``
    (a reader that numbers vertices differently) is it compared in the
    canonical stored form. Returns whether it matched (if not, nothing is
    left on disk).
    """
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.verify{path.suffix}")
    try:
        write_mesh(tmp, Mesh(V, F, name=name, metadata={"unit": "millimeter"}))
        mesh = read_mesh(tmp)
        back = (mesh.vertices, mesh.faces)
        if not _same(back, (V, F)) and not _same(stored_form(*back, precision=np.float64),
                                                 (V, F)):
            return False
        os.replace(tmp, path)
        return True
    finally:
        if tmp.exists():
            tmp.unlink()


def export_printable(path, V, F, *, force: bool = False, name: str = "geotex",
                     report: CheckReport | None = None) -> CheckReport:
    """Write ``(V, F)`` for printing, only if the file as written is printable.

    The solid is rounded to the precision the format stores (float32 for
    STL), equal corners are welded as a reader would, slivers the rounding
    broke are collapsed (:func:`~geotex.printing.stored.printable_stored_solid`),
    and the verdict is computed on exactly those arrays. The file is written
    to a temporary sibling, read back and compared with the judged arrays,
    and only then renamed to ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        Output file; ``.stl`` (binary) or ``.3mf`` (millimetres) for printers,
        ``.obj``/``.ply``/``.off`` also accepted.
    V : array_like, (n, 3) float64
        Vertex positions in millimetres.
    F : array_like, (m, 3) int64
    force : bool, optional
        Write even if the check fails (the report still says why).
    name : str, optional
        Object name stored in formats that have one.
    report : CheckReport, optional
        A report already computed; reused only when its ``digest`` matches
        the arrays as stored (for example the report of
        :func:`geotex.mapping.textured_solid`), otherwise recomputed.

    Returns
    -------
    CheckReport
        The report of the written (or refused) file's contents.

    Raises
    ------
    NotPrintableError
        If the stored solid is not printable and ``force`` is false; nothing
        is written.
    InputError
        If the extension is not a print format or the arrays are malformed.
    GeotexError
        If the file does not read back as the judged solid.
    """
    path = Path(path)
    if path.suffix.lower() not in PRINT_FORMATS:
        raise InputError(f"{path}: cannot export a print to '{path.suffix}'; "
                         f"use one of {', '.join(PRINT_FORMATS)}")
    V, F = as_mesh_arrays(V, F)
    precision = stored_precision(path.suffix)
    if (report is not None and (report.printable or force)
            and np.array_equal(V.astype(precision), V) and report.digest == mesh_digest(V, F)
            and _verified_write(path, V, F, name)):
        return report           # judged exactly as given, and the file reads back as that
    Vs, Fs = stored_form(V, F, precision=precision)
    if report is None or report.digest != mesh_digest(Vs, Fs):
        solid = printable_stored_solid(V, F, precision=precision)
        Vs, Fs, report = solid.vertices, solid.faces, solid.report
    if not report.printable and not force:
        raise NotPrintableError(
            f"refusing to write {path}: not printable as stored "
            f"({'; '.join(report.reasons)}); repair the mesh first", report)
    if not _verified_write(path, Vs, Fs, name):
        raise GeotexError(f"{path}: the written file does not read back as the solid "
                          "that was checked (a bug: please report it); nothing written")
    return report
