"""The validity report: is a triangle mesh a printable solid, and if not, why."""

from __future__ import annotations

import json
import math
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from geotex.check.intersections import self_intersecting_pairs, self_intersecting_pairs_touching
from geotex.check.nesting import component_nesting_depth
from geotex.mesh.arrays import as_mesh_arrays, mesh_digest
from geotex.errors import InputError
from geotex.progress import report
from geotex.mesh.solid import manifold_status
from geotex.mesh.geometry import bounding_box, component_volumes, degenerate_faces
from geotex.mesh.topology import (duplicate_face_groups, edge_topology, face_components,
                                  non_manifold_vertices, position_welded_faces,
                                  referenced_vertices, repeated_positions)

__all__ = ["CheckReport", "check_mesh", "recheck_moved", "LARGE_COORDINATE", "CHECK_STAGES"]

#: Stage names passed to the ``progress`` callback of :func:`check_mesh`.
CHECK_STAGES = ("topology", "self-intersections", "manifold3d")

#: Coordinates beyond this magnitude get a warning (unit mix-ups, float32 limits).
LARGE_COORDINATE = 1e9


@dataclass
class CheckReport:
    """Validity report of a triangle mesh as a 3D-printable solid.

    Counts describe the mesh as given (no welding beyond what the file reader
    did).  ``examples`` holds the first offending elements of each kind.

    Attributes
    ----------
    printable : bool
        Whether the mesh is one or more closed, edge- and vertex-manifold,
        consistently and correctly oriented shells with positive total volume,
        no degenerate or duplicate faces and no self-intersections.
    reasons : list of str
        Why it is not printable (empty when printable).
    warnings : list of str
        Things worth knowing that do not prevent printing.
    digest : str or None
        :func:`geotex.mesh.arrays.mesh_digest` of the arrays judged: a writer
        reuses the report only for exactly these arrays.
    """

    vertices: int
    faces: int
    edges: int
    components: int
    boundary_edges: int
    non_manifold_edges: int
    non_manifold_vertices: int
    inconsistent_edges: int
    orientation_consistent: bool
    outward: bool | None
    volume: float
    degenerate_faces: int
    duplicate_faces: int
    self_intersecting_pairs: int | None
    self_intersections_checked: bool
    unreferenced_vertices: int
    duplicate_vertex_positions: int
    euler_characteristic: int
    genus: int | None
    manifold3d_status: str
    bbox_min: list
    bbox_max: list
    printable: bool
    reasons: list = field(default_factory=list)
    warnings: list = field(default_factory=list)
    examples: dict = field(default_factory=dict)
    source: str | None = None
    digest: str | None = None

    @property
    def bbox_size(self) -> list:
        """Bounding-box extent per axis."""
        return [float(b - a) for a, b in zip(self.bbox_min, self.bbox_max)]

    @property
    def watertight(self) -> bool:
        """Closed (no boundary edges) and edge-manifold, with at least one face."""
        return self.faces > 0 and self.boundary_edges == 0 and self.non_manifold_edges == 0

    @property
    def manifold(self) -> bool:
        """Edge- and vertex-manifold."""
        return self.non_manifold_edges == 0 and self.non_manifold_vertices == 0

    def to_dict(self) -> dict:
        """Return a JSON-ready dict (non-finite floats become ``None``)."""
        d = asdict(self)
        d["bbox_size"] = self.bbox_size
        d["watertight"] = self.watertight
        d["manifold"] = self.manifold
        return _finite(d)

    def to_json(self, **kwargs) -> str:
        """Return the report as one JSON object."""
        return json.dumps(self.to_dict(), **kwargs)

    def summary(self) -> str:
        """Return a human-readable multi-line report ending with the verdict."""
        g = "n/a" if self.genus is None else str(self.genus)
        si = ("not checked" if not self.self_intersections_checked
              else str(self.self_intersecting_pairs))
        out = "n/a" if self.outward is None else ("yes" if self.outward else "no")
        lines = [
            f"vertices:                  {self.vertices}",
            f"faces:                     {self.faces}",
            f"edges:                     {self.edges}",
            f"connected components:      {self.components}",
            f"boundary edges:            {self.boundary_edges}",
            f"non-manifold edges:        {self.non_manifold_edges}",
            f"non-manifold vertices:     {self.non_manifold_vertices}",
            f"orientation consistent:    {'yes' if self.orientation_consistent else 'no'}"
            + ("" if self.orientation_consistent else f" ({self.inconsistent_edges} edges)"),
            f"outward oriented:          {out}",
            f"enclosed volume:           {self.volume:.6g}",
            f"degenerate faces:          {self.degenerate_faces}",
            f"duplicate faces:           {self.duplicate_faces}",
            f"self-intersecting pairs:   {si}",
            f"unreferenced vertices:     {self.unreferenced_vertices}",
            f"euler characteristic:      {self.euler_characteristic}",
            f"genus:                     {g}",
            f"manifold3d status:         {self.manifold3d_status}",
            "bounding box:              "
            + " .. ".join("(" + ", ".join(f"{c:.6g}" for c in b) + ")"
                          for b in (self.bbox_min, self.bbox_max))
            + "  size (" + ", ".join(f"{c:.6g}" for c in self.bbox_size) + ")",
        ]
        for w in self.warnings:
            lines.append(f"warning: {w}")
        lines.append(f"printable: {'yes' if self.printable else 'no'}")
        lines.extend(f"  - {r}" for r in self.reasons)
        return "\n".join(lines)


def _finite(obj):
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return obj


def _first(arr, k):
    return np.asarray(arr)[:k].tolist()


def _unit_coordinates(V, lo, hi, m):
    """Coordinates centred on the box ``lo .. hi`` and scaled to unit half-extent, and the scale.

    Geometric predicates run on these: the verdict does not depend on
    position or scale, and huge coordinates cannot overflow.
    """
    center = 0.5 * lo + 0.5 * hi
    scale = float(np.max(0.5 * hi - 0.5 * lo)) if m else 1.0
    scale = scale if scale > 0 and math.isfinite(scale) else 1.0
    return (V - center) / scale, scale


def check_mesh(V, F, *, self_intersections: bool = True, manifold3d: bool = True,
               max_examples: int = 5, source: str | None = None, progress=None
               ) -> CheckReport:
    """Compute the validity report of a triangle mesh as a printable solid.

    Parameters
    ----------
    V : array_like, (n, 3) float64
        Vertex positions.
    F : array_like, (m, 3) int64
        Triangles.
    self_intersections : bool, optional
        Run the self-intersection test (the most expensive part).  When false
        the report says it was not checked and the mesh is not called
        printable on that count alone.
    manifold3d : bool, optional
        Also ask manifold3d whether it takes the mesh as a solid (a second
        opinion, costing about half the self-intersection test; what it
        checks, closed, manifold and consistently oriented, the tests above
        check too). When false the
        report's ``manifold3d_status`` is ``"not run"``.
    max_examples : int, optional
        How many offending elements of each kind to keep in ``examples``.
    source : str, optional
        File name recorded in the report.
    progress : callable, optional
        Called with a stage name as each of the stages ``CHECK_STAGES``
        starts (see :mod:`geotex.progress`).

    Returns
    -------
    CheckReport

    Raises
    ------
    InputError
        If ``V`` or ``F`` are malformed.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    >>> F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> check_mesh(V, F).printable
    True
    """
    V, F = as_mesh_arrays(V, F)
    n, m = V.shape[0], F.shape[0]
    k = max_examples
    examples: dict[str, list] = {}

    report(progress, "topology")
    used = referenced_vertices(F, n)
    unreferenced = int(n - used.sum())
    lo, hi = bounding_box(V[used] if m else V)
    Vn, scale = _unit_coordinates(V, lo, hi, m)

    topo = edge_topology(F, n)
    boundary = topo.boundary
    nm_edges = topo.non_manifold
    inconsistent = topo.inconsistent
    nm_verts = non_manifold_vertices(F, n, topo)
    degenerate = degenerate_faces(Vn, F)
    duplicates = duplicate_face_groups(F, topo)
    count, labels = face_components(F, n)

    # exact duplicate positions among referenced vertices (unwelded seams)
    dup_positions = repeated_positions(V[used]) if m else 0

    # closedness per component
    closed_comp = np.ones(count, dtype=bool)
    if boundary.size or nm_edges.size:
        ef = topo.edge_faces()
        bad_edges = np.concatenate([boundary, nm_edges])
        closed_comp[labels[ef[bad_edges, 0]]] = False

    norm_vol = component_volumes(Vn, F, labels, count) if m else np.zeros(0)
    with np.errstate(over="ignore", invalid="ignore"):   # huge coordinates: inf, not NaN
        unit_volume = float(norm_vol.sum()) if m else 0.0
        total_volume = float(unit_volume * np.float64(scale) ** 3) if unit_volume else 0.0

    outward: bool | None = None
    if m and inconsistent.size == 0 and closed_comp.all():
        depth = component_nesting_depth(Vn, F, labels, count, closed_comp)
        expected = np.where(depth % 2 == 0, 1.0, -1.0)
        wrong = np.flatnonzero(np.sign(norm_vol) != expected)
        outward = bool(wrong.size == 0 and norm_vol.sum() > 0)
        if wrong.size:
            examples["inward_components"] = _first(wrong, k)

    chi = int(used.sum()) - int(topo.edges.shape[0]) + m
    edge_count = int(topo.edges.shape[0])
    bad_edges = np.concatenate([boundary, nm_edges, inconsistent])
    # what the self-intersection search needs of the edge topology: the ends of
    # edges not used once each way (boundary, non-manifold or inconsistent ones)
    unpaired = np.zeros(n, dtype=bool)
    unpaired[topo.edges[bad_edges].ravel()] = True
    # only the rows of bad edges are read again (examples): the edge topology
    # (~100 bytes per face) is not held through the self-intersection search
    # (the memory peak) nor while manifold3d builds its copy
    edges = topo.edges if bad_edges.size else None
    dup_topo = topo if duplicates.size and not dup_positions else None   # groups the duplicates
    del topo, labels, Vn, bad_edges

    pairs = None
    report(progress, "self-intersections")
    if self_intersections and m:
        pairs = (self_intersecting_pairs(V, position_welded_faces(V, F)) if dup_positions
                 else self_intersecting_pairs(V, F, topology=dup_topo, unpaired_vertices=unpaired,
                                              distinct_faces=duplicates.size == 0))
    elif self_intersections:
        pairs = np.zeros((0, 2), dtype=np.int64)
    del dup_topo, unpaired
    genus = None
    closed_manifold = (m > 0 and boundary.size == 0 and nm_edges.size == 0
                       and nm_verts.size == 0 and inconsistent.size == 0)
    if closed_manifold and (2 * count - chi) % 2 == 0:
        genus = (2 * count - chi) // 2
    report(progress, "manifold3d")
    status = "Empty" if not m else manifold_status(V, F) if manifold3d else "not run"
    return _verdict(V, F, k, edges=edges, edge_count=edge_count, count=count, boundary=boundary,
                    nm_edges=nm_edges, nm_verts=nm_verts, inconsistent=inconsistent,
                    outward=outward, norm_vol=norm_vol, total_volume=total_volume,
                    degenerate=degenerate, duplicates=duplicates, pairs=pairs, status=status,
                    unreferenced=unreferenced, dup_positions=dup_positions, chi=chi,
                    genus=genus, box=(lo, hi), examples=examples, source=source)


def recheck_moved(V_before, V, F, before: CheckReport, *, max_examples: int = 5
                  ) -> CheckReport | None:
    """The report of a mesh whose vertices moved, from its report before, by local work.

    Gives exactly ``check_mesh(V, F, manifold3d=False, max_examples=...)``
    when ``before`` is ``check_mesh(V_before, F, manifold3d=False, ...)``
    and the mesh is a simple case; returns ``None`` otherwise (the caller
    then runs :func:`check_mesh`).  Only faces at moved vertices change
    shape, so: the self-intersecting pairs are the old ones without such a
    face plus :func:`~geotex.check.intersections.self_intersecting_pairs_touching`
    of those faces; degenerate faces are re-tested among them; the topology
    (the same ``F``) is unchanged; the volume and orientation are recomputed
    (a pass over the faces).

    Parameters
    ----------
    V_before : array_like, (n, 3) float64
        The vertices ``before`` judged (checked against its ``digest``).
    V : array_like, (n, 3) float64
        The moved vertices.
    F : array_like, (m, 3) int64
        The faces of both.
    before : CheckReport
        Judged with ``manifold3d=False`` and ``max_examples`` at least the
        numbers of crossing pairs and of degenerate faces (complete lists).
    max_examples : int, optional
        As in :func:`check_mesh`.

    Returns
    -------
    CheckReport or None
        ``None`` unless ``before`` describes ``(V_before, F)`` with complete
        example lists, and the mesh is one closed, manifold, consistently
        oriented shell without duplicate faces, unreferenced or repeated
        vertices, whose bounding box the moves do not change, and no moved
        vertex lands on another vertex's position.

    Raises
    ------
    InputError
        Malformed arrays, or ``V`` and ``V_before`` of different shapes.
    """
    V, F = as_mesh_arrays(V, F)
    V_before = np.ascontiguousarray(V_before, dtype=np.float64)
    V = np.ascontiguousarray(V)
    n, m = V.shape[0], F.shape[0]
    if V_before.shape != V.shape:
        raise InputError(f"V_before has shape {V_before.shape}, V has {V.shape}")
    b = before
    ex = b.examples
    pairs_before = ex.get("self_intersecting_pairs", [])
    degenerate_before = ex.get("degenerate_faces", [])
    if (m == 0 or b.manifold3d_status != "not run" or not b.self_intersections_checked
            or b.components != 1 or b.boundary_edges or b.non_manifold_edges
            or b.non_manifold_vertices or b.inconsistent_edges or b.duplicate_faces
            or b.unreferenced_vertices or b.duplicate_vertex_positions
            or b.faces != m or b.vertices != n
            or len(pairs_before) != b.self_intersecting_pairs
            or len(degenerate_before) != b.degenerate_faces
            or b.digest != mesh_digest(V_before, F)):
        return None
    lo, hi = bounding_box(V)
    if not (np.array_equal(lo, b.bbox_min) and np.array_equal(hi, b.bbox_max)):
        return None               # the normalisations of the predicates would change
    diff = V.view(np.uint64) != V_before.view(np.uint64)      # bits: -0.0 moved too
    moved = np.flatnonzero(diff[:, 0] | diff[:, 1] | diff[:, 2])
    del diff
    if moved.size == 0:
        return replace(b, examples={key: val[:max_examples] for key, val in ex.items()})
    # a moved vertex on another vertex's position: check_mesh would weld for the search
    same_x = np.flatnonzero(np.isin(V[:, 0], V[moved, 0]))
    if repeated_positions(V[same_x]):
        return None
    at = np.zeros(n, dtype=bool)
    at[moved] = True
    touched = np.flatnonzero(at[F[:, 0]] | at[F[:, 1]] | at[F[:, 2]])
    hit = np.zeros(m, dtype=bool)
    hit[touched] = True
    Vn, scale = _unit_coordinates(V, lo, hi, m)
    old_deg = np.asarray(degenerate_before, dtype=np.int64)
    degenerate = np.union1d(old_deg[~hit[old_deg]],
                            touched[degenerate_faces(Vn, F[touched])])
    old = np.asarray(pairs_before, dtype=np.int64).reshape(-1, 2)
    old = old[~(hit[old[:, 0]] | hit[old[:, 1]])]
    new = self_intersecting_pairs_touching(V, F, touched)
    key = np.sort(np.concatenate([old[:, 0] * m + old[:, 1], new[:, 0] * m + new[:, 1]]))
    pairs = np.stack([key // m, key % m], axis=1)
    # one closed shell (nesting depth 0): outward when its volume is positive
    norm_vol = component_volumes(Vn, F, np.zeros(m, dtype=np.int64), 1)
    with np.errstate(over="ignore", invalid="ignore"):
        unit_volume = float(norm_vol.sum())
        total_volume = float(unit_volume * np.float64(scale) ** 3) if unit_volume else 0.0
    examples: dict[str, list] = {}
    wrong = np.flatnonzero(np.sign(norm_vol) != 1.0)
    outward = bool(wrong.size == 0 and norm_vol.sum() > 0)
    if wrong.size:
        examples["inward_components"] = _first(wrong, max_examples)
    none = np.zeros(0, dtype=np.int64)
    return _verdict(V, F, max_examples, edges=None, edge_count=b.edges, count=1, boundary=none,
                    nm_edges=none, nm_verts=none, inconsistent=none, outward=outward,
                    norm_vol=norm_vol, total_volume=total_volume, degenerate=degenerate,
                    duplicates=none, pairs=pairs, status=b.manifold3d_status, unreferenced=0,
                    dup_positions=0, chi=b.euler_characteristic, genus=b.genus,
                    box=(lo, hi), examples=examples, source=b.source)


def _verdict(V, F, k, *, edges, edge_count, count, boundary, nm_edges, nm_verts, inconsistent, outward,
             norm_vol, total_volume, degenerate, duplicates, pairs, status, unreferenced,
             dup_positions, chi, genus, box, examples, source) -> CheckReport:
    """The report of :func:`check_mesh` from its measurements (reasons, warnings, examples).

    ``edges`` (the edge rows) is read only for the examples of bad edges.
    """
    n, m = V.shape[0], F.shape[0]
    lo, hi = box
    reasons: list[str] = []
    warnings: list[str] = []
    # verdict
    if m == 0:
        reasons.append("the mesh has no faces" + (" (a point cloud)" if n else ""))
    if boundary.size:
        reasons.append(f"not watertight: {boundary.size} boundary edges")
        examples["boundary_edges"] = edges[boundary[:k]].tolist()
    if nm_edges.size:
        reasons.append(f"{nm_edges.size} non-manifold edges (used by more than two faces)")
        examples["non_manifold_edges"] = edges[nm_edges[:k]].tolist()
    if nm_verts.size:
        reasons.append(f"{nm_verts.size} non-manifold vertices (faces around them do not form one fan)")
        examples["non_manifold_vertices"] = _first(nm_verts, k)
    if inconsistent.size:
        reasons.append(f"inconsistent face orientation: {inconsistent.size} edges "
                       "have both neighbouring faces running the same way")
        examples["inconsistent_edges"] = edges[inconsistent[:k]].tolist()
    if outward is False:
        if norm_vol.sum() <= 0:
            reasons.append(f"faces point inward: enclosed volume is {total_volume:.6g}")
        else:
            reasons.append(f"{len(examples['inward_components'])} components are oriented "
                           "the wrong way (inside out)")
    if degenerate.size:
        reasons.append(f"{degenerate.size} degenerate (zero-area) faces")
        examples["degenerate_faces"] = _first(degenerate, k)
    if duplicates.size:
        reasons.append(f"{duplicates.size} duplicate faces")
        examples["duplicate_faces"] = _first(duplicates, k)
    if pairs is not None and pairs.shape[0]:
        reasons.append(f"{pairs.shape[0]} self-intersecting face pairs")
        examples["self_intersecting_pairs"] = pairs[:k].tolist()
    if pairs is None and m:
        reasons.append("self-intersections were not checked")
    if m and status not in ("NoError", "not run") and not reasons:
        reasons.append(f"manifold3d rejects the mesh ({status})")

    if unreferenced:
        warnings.append(f"{unreferenced} unreferenced vertices")
    if dup_positions:
        warnings.append(f"{dup_positions} vertices repeat another vertex's position "
                        "(unwelded seams, or shells that touch)")
    big = float(np.max(np.abs(V))) if n else 0.0
    if big > LARGE_COORDINATE:
        warnings.append(f"very large coordinates (max |c| = {big:.3g}); check the unit")
    if m and not np.isfinite(total_volume):
        warnings.append("enclosed volume overflows float64")

    return CheckReport(
        vertices=n, faces=m, edges=edge_count, components=count,
        boundary_edges=int(boundary.size), non_manifold_edges=int(nm_edges.size),
        non_manifold_vertices=int(nm_verts.size), inconsistent_edges=int(inconsistent.size),
        orientation_consistent=bool(inconsistent.size == 0), outward=outward,
        volume=total_volume, degenerate_faces=int(degenerate.size),
        duplicate_faces=int(duplicates.size),
        self_intersecting_pairs=None if pairs is None else int(pairs.shape[0]),
        self_intersections_checked=pairs is not None,
        unreferenced_vertices=unreferenced, duplicate_vertex_positions=dup_positions,
        euler_characteristic=chi, genus=genus, manifold3d_status=status,
        bbox_min=[float(x) for x in lo], bbox_max=[float(x) for x in hi],
        printable=not reasons, reasons=reasons, warnings=warnings,
        examples=examples, source=source, digest=mesh_digest(V, F))
