"""Print export: write a solid only when it passes the printability check."""

from __future__ import annotations

from pathlib import Path

from geotex.check.report import CheckReport, check_mesh
from geotex.errors import InputError, NotPrintableError
from geotex.io import write_mesh
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.record import Mesh

__all__ = ["export_printable", "PRINT_FORMATS"]

#: Extensions accepted by :func:`export_printable`.
PRINT_FORMATS = (".stl", ".3mf", ".obj", ".ply", ".off")


def export_printable(path, V, F, *, force: bool = False, name: str = "geotex",
                     report: CheckReport | None = None) -> CheckReport:
    """Write ``(V, F)`` for printing after checking it is a printable solid.

    Parameters
    ----------
    path : str or os.PathLike
        Output file; ``.stl`` (binary) or ``.3mf`` (millimetres) for printers,
        ``.obj``/``.ply``/``.off`` also accepted.  Written atomically.
    V : array_like, (n, 3) float64
        Vertex positions in millimetres.
    F : array_like, (m, 3) int64
    force : bool, optional
        Write even if the check fails (the report still says why).
    name : str, optional
        Object name stored in formats that have one.
    report : CheckReport, optional
        A report already computed for exactly these arrays.

    Returns
    -------
    CheckReport
        The report of the written (or refused) solid.

    Raises
    ------
    NotPrintableError
        If the solid is not printable and ``force`` is false; nothing is written.
    InputError
        If the extension is not a print format or the arrays are malformed.
    """
    path = Path(path)
    if path.suffix.lower() not in PRINT_FORMATS:
        raise InputError(f"{path}: cannot export a print to '{path.suffix}'; "
                         f"use one of {', '.join(PRINT_FORMATS)}")
    V, F = as_mesh_arrays(V, F)
    report = report if report is not None else check_mesh(V, F)
    if not report.printable and not force:
        raise NotPrintableError(
            f"refusing to write {path}: not printable ({'; '.join(report.reasons)}); "
            "repair the mesh first", report)
    write_mesh(path, Mesh(V, F, name=name, metadata={"unit": "millimeter"}))
    return report
