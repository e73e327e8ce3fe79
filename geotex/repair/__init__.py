"""Mesh repair: turn a broken triangle mesh into a printable solid where possible.

Each step is a free function returning new arrays and a count; ``repair_mesh``
runs them in order and records what changed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from geotex.check.intersections import self_intersecting_pairs
from geotex.check.report import CheckReport, check_mesh
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.topology import face_components
from geotex.progress import report
from geotex.repair.faces import without_degenerate_faces, without_duplicate_faces
from geotex.repair.holes import filled_holes, split_non_manifold
from geotex.repair.intersections import union_of_shells, without_intersecting_faces
from geotex.repair.orient import consistently_oriented, outward_oriented
from geotex.repair.weld import default_weld_tolerance, welded, without_unreferenced_vertices

__all__ = [
    "RepairResult", "repair_mesh", "welded", "without_unreferenced_vertices",
    "without_degenerate_faces", "without_duplicate_faces", "split_non_manifold",
    "filled_holes", "consistently_oriented", "outward_oriented", "union_of_shells",
    "without_intersecting_faces", "default_weld_tolerance", "REPAIR_STAGES",
    "MAX_VOLUME_LOSS",
]

#: Largest fraction of the volume a repair may lose before it is flagged.
MAX_VOLUME_LOSS = 0.01

#: Stage names passed to the ``progress`` callback of :func:`repair_mesh`.
REPAIR_STAGES = ("weld", "faces", "orientation", "holes", "self-intersections",
                 "final check")


@dataclass
class RepairResult:
    """Outcome of :func:`repair_mesh`.

    Attributes
    ----------
    vertices : numpy.ndarray, (n, 3) float64
    faces : numpy.ndarray, (m, 3) int64
    changes : list of str
        One line per step that changed something, in order.
    report : CheckReport
        Validity report of the repaired mesh.
    warnings : list of str
        One line per way the repair changed the solid itself rather than
        fixing it: cutting self-intersections changed the number of shells,
        or lost more than :data:`MAX_VOLUME_LOSS` of the volume.  Such a
        result may be printable yet not be the object the input described.
    """

    vertices: np.ndarray
    faces: np.ndarray
    changes: list = field(default_factory=list)
    report: CheckReport | None = None
    warnings: list = field(default_factory=list)

    @property
    def printable(self) -> bool:
        """Whether the repaired mesh passes the printability check."""
        return bool(self.report is not None and self.report.printable)

    @property
    def faithful(self) -> bool:
        """Whether the repair kept the solid (no :attr:`warnings`)."""
        return not self.warnings


def _signed_volume(V: np.ndarray, F: np.ndarray) -> float:
    if not F.shape[0]:
        return 0.0
    c = V[F].mean(axis=(0, 1))          # about the centroid: less cancellation
    A, B, C = V[F[:, 0]] - c, V[F[:, 1]] - c, V[F[:, 2]] - c
    return float(np.einsum("ij,ij->i", A, np.cross(B, C)).sum() / 6.0)


def repair_mesh(V, F, *, weld_tolerance: float | None = None, fill_holes: bool = True,
                max_hole_edges: int | None = None, resolve_intersections: bool = True,
                progress=None) -> RepairResult:
    """Repair a triangle mesh towards a printable solid.

    Steps, in order: weld vertices closer than ``weld_tolerance``; drop
    degenerate faces; resolve duplicate faces (opposite copies cancel);
    split non-manifold edges and vertices; orient faces consistently; fill
    holes; orient shells outward (cavities inward); resolve
    self-intersections (boolean union of closed shells, then deleting
    crossing faces and closing the holes); drop unreferenced vertices.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    weld_tolerance : float, optional
        Absolute merge distance; default ``1e-6`` times the bounding-box
        diagonal.  ``0`` merges exact duplicates only.
    fill_holes : bool, optional
        Close boundary loops.
    max_hole_edges : int, optional
        Largest hole to close, in boundary edges (all by default).
    resolve_intersections : bool, optional
        Try to remove self-intersections.
    progress : callable, optional
        Called with a stage name as each of ``REPAIR_STAGES`` starts.

    Returns
    -------
    RepairResult
        The repaired arrays, the list of changes, the final report and the
        warnings (a repair that changed the number of shells or lost more
        than :data:`MAX_VOLUME_LOSS` of the volume while cutting
        self-intersections away).  The input arrays are not modified.

    Raises
    ------
    InputError
        If ``V`` or ``F`` are malformed.
    """
    V, F = as_mesh_arrays(V, F)
    changes: list[str] = []
    warnings: list[str] = []

    def note(count: int, text: str):
        if count:
            changes.append(text.format(count))

    report(progress, "weld")
    tol = default_weld_tolerance(V) if weld_tolerance is None else float(weld_tolerance)
    V, F, k = welded(V, F, tolerance=tol)
    note(k, "welded {} vertices" + (f" (tolerance {tol:.3g})" if tol else ""))
    report(progress, "faces")
    F, k = without_degenerate_faces(V, F)
    note(k, "removed {} degenerate faces")
    F, k = without_duplicate_faces(F)
    note(k, "removed {} duplicate faces")
    report(progress, "orientation")
    V, F, k = split_non_manifold(V, F)
    note(k, "split non-manifold edges and vertices ({} vertices added)")
    F, k = consistently_oriented(F)
    note(k, "flipped {} faces for consistent orientation")
    report(progress, "holes")
    if fill_holes:
        V, F, k = filled_holes(V, F, max_hole_edges=max_hole_edges)
        note(k, "filled holes with {} faces")
    F, k = outward_oriented(V, F)
    note(k, "reoriented {} shells outward")
    report(progress, "self-intersections")
    if resolve_intersections and F.shape[0]:
        pairs = self_intersecting_pairs(V, F)
        if pairs.shape[0]:
            count, _ = face_components(F, V.shape[0])
            merged = union_of_shells(V, F) if count > 1 else None
            if merged is not None and merged[1].shape[0]:
                V, F = merged
                changes.append(f"merged {count} overlapping shells by boolean union "
                               f"({pairs.shape[0]} intersecting face pairs)")
                pairs = self_intersecting_pairs(V, F)
            if pairs.shape[0]:
                before = pairs.shape[0]
                V2, F2, left = without_intersecting_faces(V, F)
                if left < before:
                    shells_before, _ = face_components(F, V.shape[0])
                    volume_before = abs(_signed_volume(V, F))
                    V, F = V2, F2
                    shells, _ = face_components(F, V.shape[0])
                    split = (f"; the solid now has {shells} shells (was {shells_before})"
                             if shells != shells_before else "")
                    changes.append(f"cut away {before - left} of {before} self-intersecting "
                                   f"face pairs and closed the holes{split}")
                    F, _ = outward_oriented(V, F)
                    if shells != shells_before:
                        warnings.append(f"cutting self-intersections split the solid into "
                                        f"{shells} shells (was {shells_before})")
                    volume = abs(_signed_volume(V, F))
                    if volume_before > 0 and \
                            volume < (1 - MAX_VOLUME_LOSS) * volume_before:
                        lost = 100 * (1 - volume / volume_before)
                        warnings.append(f"cutting self-intersections lost {lost:.1f}% of "
                                        "the volume")
    V, F, k = without_unreferenced_vertices(V, F)
    note(k, "removed {} unreferenced vertices")
    report(progress, "final check")
    return RepairResult(vertices=V, faces=F, changes=changes, report=check_mesh(V, F),
                        warnings=warnings)
