"""Print export: write a solid only when the file, as written, is printable.

The verdict is computed on the coordinates the format stores
(:mod:`geotex.printing.stored`: float32 for STL), and the written file is
read back and compared with the judged arrays before it takes its final name.
A :class:`StagedWrite` does that writing in a background thread while the
solid is still being judged, and gives the file its name only once the
verdict on exactly those arrays says printable.
"""

from __future__ import annotations

import os
import threading
from pathlib import Path

import numpy as np

from geotex.check.report import CheckReport
from geotex.errors import GeotexError, InputError, NotPrintableError
from geotex.io import read_mesh, write_mesh
from geotex.mesh.arrays import as_mesh_arrays, mesh_digest
from geotex.mesh.record import Mesh
from geotex.printing.stored import (StoredSolid, printable_stored_solid, stored_form,
                                    stored_precision)

__all__ = ["export_printable", "StagedWrite", "PRINT_FORMATS", "printable_stored_solid",
           "stored_form", "stored_precision", "StoredSolid", "written_form"]

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


def _written_back(tmp: Path, V, F, name: str) -> bool:
    """Write ``(V, F)`` to ``tmp`` and say whether it reads back as them.

    The file is read back as it is; only when that differs from ``(V, F)``
    (a reader that numbers vertices differently) is it compared in the
    canonical stored form. ``tmp`` stays on disk either way.
    """
    write_mesh(tmp, Mesh(V, F, name=name, metadata={"unit": "millimeter"}))
    mesh = read_mesh(tmp)
    back = (mesh.vertices, mesh.faces)
    return _same(back, (V, F)) or _same(stored_form(*back, precision=np.float64), (V, F))


def _verified_write(path: Path, V, F, name: str) -> bool:
    """Write, read the file back, and give it its final name only if it matches.

    Returns whether it matched (if not, nothing is left on disk).
    """
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.verify{path.suffix}")
    try:
        if not _written_back(tmp, V, F, name):
            return False
        os.replace(tmp, path)
        return True
    finally:
        if tmp.exists():
            tmp.unlink()


class StagedWrite:
    """A print file written in the background while its solid is judged.

    Calling the object with the arrays a check is about to judge (the
    ``on_stored`` hook of :func:`~geotex.printing.stored.printable_stored_solid`
    and :func:`geotex.mapping.textured_solid`) starts writing them to a
    hidden temporary sibling of ``path`` in a thread, reading the file back
    and comparing it with the arrays (as :func:`export_printable` does). A
    later call replaces that file. :func:`export_printable` given
    ``staged=`` renames the file to ``path`` only when the report it is
    given judges exactly the staged arrays and says printable (or ``force``);
    otherwise the staged file is deleted and the solid written as usual.
    Leaving the ``with`` block (or :meth:`discard`) deletes an unused file, so
    no partial or unjudged output is ever left under ``path``.

    Parameters
    ----------
    path : str or os.PathLike
        The final output file (one of :data:`PRINT_FORMATS`).
    name : str, optional
        Object name stored in formats that have one.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> from geotex.mesh.primitives import box
    >>> V, F = box((0, 0, 0), (10, 10, 10))
    >>> out = pathlib.Path(tempfile.mkdtemp()) / "part.stl"
    >>> with StagedWrite(out) as staged:
    ...     solid = printable_stored_solid(V, F, on_stored=staged)
    ...     rep = export_printable(out, solid.vertices, solid.faces,
    ...                            report=solid.report, staged=staged)
    >>> out.exists(), rep.printable, sorted(p.name for p in out.parent.iterdir())
    (True, True, ['part.stl'])
    """

    def __init__(self, path, *, name: str = "geotex"):
        self.path = Path(path)
        self.name = name
        self._thread = None
        self._arrays = None
        self._tmp = None
        self._result = None
        self._count = 0

    def __call__(self, V, F) -> None:
        """Start writing ``(V, F)`` (float64 / int64, as judged) in the background."""
        self.discard()
        self._count += 1
        tmp = self.path.with_name(f".{self.path.stem}.{os.getpid()}.staged{self._count}"
                                  f"{self.path.suffix}")
        self._arrays, self._tmp, self._result = (V, F), tmp, None

        def work():
            try:
                self._result = _written_back(tmp, V, F, self.name)
            except Exception as exc:             # seen by commit: the usual path reports it
                self._result = exc

        self._thread = threading.Thread(target=work, name="geotex-staged-write", daemon=True)
        self._thread.start()

    def _wait(self):
        if self._thread is not None:
            self._thread.join()
            self._thread = None

    def commit(self, V, F) -> bool:
        """Rename the staged file to ``path`` if it holds exactly ``(V, F)``, read back.

        The caller has judged ``(V, F)`` printable (see :func:`export_printable`).
        Returns whether it was renamed; if not, the staged file is deleted.
        """
        self._wait()
        staged = self._arrays
        ok = (staged is not None and self._result is True
              and all(a is b or (a.shape == b.shape and np.array_equal(a, b))
                      for a, b in zip(staged, (V, F))))
        if ok:
            os.replace(self._tmp, self.path)
            self._tmp = None
        self.discard()
        return ok

    def discard(self) -> None:
        """Wait for a running write and delete its file (if not committed)."""
        self._wait()
        if self._tmp is not None and self._tmp.exists():
            self._tmp.unlink()
        self._arrays, self._tmp, self._result = None, None, None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.discard()
        return False


def export_printable(path, V, F, *, force: bool = False, name: str = "geotex",
                     report: CheckReport | None = None,
                     staged: StagedWrite | None = None) -> CheckReport:
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
    staged : StagedWrite, optional
        A write of the judged arrays already under way (for ``path``): used
        instead of writing again when ``report`` judges exactly its arrays,
        deleted otherwise.

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
    if staged is not None and Path(staged.path) != path:
        raise InputError(f"{path}: the staged write is for {staged.path}")
    if (report is not None and (report.printable or force)
            and np.array_equal(V.astype(precision), V) and report.digest == mesh_digest(V, F)
            and ((staged is not None and staged.commit(V, F))
                 or _verified_write(path, V, F, name))):
        return report           # judged exactly as given, and the file reads back as that
    if staged is not None:
        staged.discard()
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
