"""Which parts of the surface get relief: masks with soft borders.

A mask selects *base faces*; a refined vertex is free (weight 1) when every
refined face around it lies in a selected base face, so an excluded face
(the flat bed face by default) keeps its exact plane and border.  With a
transition width, the weight rises from 0 at the nearest held vertex to 1 at
``width`` millimetres (straight-line distance, a close stand-in for the
distance along the surface at widths below the part's feature size) along a
``linear``, ``smoothstep`` or ``ease-in`` curve.

Selectors (each a boolean per base face):

* angle: faces whose normal is within ``bottom_angle`` degrees of -z (the
  bed) or ``top_angle`` of +z;
* a face-selection file (:func:`face_selection`): a JSON list of face
  indices, or ``{"faces": [...]}``; or a painted copy of the part, a PLY
  with per-face or per-vertex colours or an OBJ with ``v x y z r g b``
  vertex colours (:func:`painted_faces`, rule below);
* geometric: a box (face centroid inside), a sphere (centroid inside), a
  normal cone (normal within an angle of a direction);
* bucket fill: faces reached from seed faces across edges whose dihedral
  angle is at most a threshold.

``select_mode="include"`` textures only the selected faces,
``"exclude"`` everything but them; angle exclusions apply in both modes.

Painted selections
    Colours are compared on 0..255 per channel; two colours match when no
    channel differs by more than ``tolerance`` (default 30).  The *base
    colour* is the most common colour of the painted mesh (of its faces for
    per-face colours, of its vertices for per-vertex ones): what the part
    looked like before painting.  A colour is *painted* when it does not
    match the base colour, or, when ``color`` is given, when it matches
    ``color``.  With per-face colours (PLY, which wins when a file has both)
    a face is selected when its colour is painted; with per-vertex colours
    when at least two of its three corners are (the majority: the selection
    border runs through the middle of the painted border, as the editor
    shows a vertex-painted stroke).  When more than half of the part is
    painted the paint is the most common colour: give ``color``.

    The painted mesh must be the part itself, in the same units and place.
    When it has the base's face count and each face's centroid is where the
    base face's is, faces correspond by index; otherwise (an editor that
    re-indexed, merged or split vertices, or triangulated differently) each
    base face takes the selection of the painted face with the nearest
    centroid (a KD tree), and the file is refused when those distances
    average more than 1 % of the base's bounding-box diagonal.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from geotex.displace.choices import CURVES, PAINT_TOLERANCE
from geotex.errors import GeotexError, InputError
from geotex.io import read_mesh_colors
from geotex.mesh.geometry import face_normals
from geotex.mesh.topology import edge_topology
from geotex.options import finite_number

__all__ = ["MaskOptions", "mask_options", "selected_faces", "face_selection_file",
           "face_selection", "painted_faces", "bucket_fill_faces", "mask_weights", "CURVES",
           "PAINT_TOLERANCE", "MAX_TRANSFER_DISTANCE"]

#: A painted mesh whose nearest face centroids lie farther than this fraction
#: of the base's diagonal on average is not a copy of the base.
MAX_TRANSFER_DISTANCE = 0.01
_MESH_SUFFIXES = (".ply", ".obj", ".off", ".stl", ".3mf", ".glb")


@dataclass(frozen=True)
class MaskOptions:
    """Masking options (see the module docstring).

    Attributes
    ----------
    bottom_angle, top_angle : float
        Degrees; 0 turns that exclusion off.  Default: bed faces within 5
        degrees of -z stay flat.
    faces : numpy.ndarray or None
        Base face indices from a selection file.
    box : tuple of 6 floats or None
        ``(x0, y0, z0, x1, y1, z1)``, mm.
    sphere : tuple of 4 floats or None
        ``(x, y, z, r)``, mm.
    normal_cone : tuple of 4 floats or None
        ``(x, y, z, degrees)``.
    fill_seeds : tuple of int
        Bucket-fill seed faces.
    fill_angle : float
        Bucket fill crosses edges with dihedral angle at most this (degrees).
    select_mode : str
        ``"include"`` or ``"exclude"`` (only used when something is selected).
    width : float
        Transition width, mm (0: hard border).
    curve : str
        One of ``CURVES``.
    """

    bottom_angle: float = 5.0
    top_angle: float = 0.0
    faces: np.ndarray | None = None
    box: tuple | None = None
    sphere: tuple | None = None
    normal_cone: tuple | None = None
    fill_seeds: tuple = ()
    fill_angle: float = 20.0
    select_mode: str = "include"
    width: float = 0.0
    curve: str = "smoothstep"


def mask_options(*, bottom_angle=5.0, top_angle=0.0, faces=None, box=None, sphere=None,
                 normal_cone=None, fill_seeds=(), fill_angle=20.0, select_mode="include",
                 width=0.0, curve="smoothstep") -> MaskOptions:
    """Validated :class:`MaskOptions`.

    Raises
    ------
    InputError
        Angles outside [0, 90] (cone: [0, 180]), a box with lo > hi, a
        non-positive radius, a negative width, unknown mode or curve.
    """
    def angle(x, name, top=90.0):
        a = finite_number(x, name=name)
        if not (0.0 <= a <= top):
            raise InputError(f"{name} must be in [0, {top:g}] degrees, got {x!r}")
        return a

    def numbers(x, k, name):
        if x is None:
            return None
        vals = tuple(finite_number(v, name=name) for v in x)
        if len(vals) != k:
            raise InputError(f"{name} needs {k} numbers, got {len(vals)}")
        return vals

    b = numbers(box, 6, "box")
    if b is not None and not all(b[i] <= b[i + 3] for i in range(3)):
        raise InputError("box needs x0 <= x1, y0 <= y1, z0 <= z1")
    s = numbers(sphere, 4, "sphere")
    if s is not None and not s[3] > 0:
        raise InputError("sphere needs a positive radius")
    c = numbers(normal_cone, 4, "normal_cone")
    if c is not None:
        angle(c[3], "normal_cone angle", 180.0)
        if np.linalg.norm(c[:3]) == 0:
            raise InputError("normal_cone needs a non-zero direction")
    if select_mode not in ("include", "exclude"):
        raise InputError(f"select_mode must be include or exclude, got {select_mode!r}")
    if curve not in CURVES:
        raise InputError(f"curve must be one of {', '.join(CURVES)}, got {curve!r}")
    w = finite_number(width, name="width")
    if w < 0:
        raise InputError(f"width must be >= 0 mm, got {width!r}")
    seeds = tuple(int(x) for x in fill_seeds)
    fa = np.asarray(faces, dtype=np.int64).ravel() if faces is not None else None
    return MaskOptions(angle(bottom_angle, "bottom_angle"), angle(top_angle, "top_angle"),
                       fa, b, s, c, seeds, angle(fill_angle, "fill_angle", 180.0),
                       select_mode, w, curve)


def face_selection_file(path) -> np.ndarray:
    """Read a JSON face-selection file: a list of face indices or ``{"faces": [...]}``.

    Returns
    -------
    numpy.ndarray, (k,) int64

    Raises
    ------
    InputError
        Missing file, not JSON, not a list of non-negative integers, or a
        mesh file (painted selections need the base: :func:`face_selection`).
    """
    p = Path(path)
    if p.suffix.lower() in _MESH_SUFFIXES:
        raise InputError(f"face selection {p}: a painted mesh is matched to the base; read it "
                         "with face_selection(path, V, F)")
    if not p.is_file():
        raise InputError(f"face selection {p}: no such file")
    try:
        data = json.loads(p.read_text())
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"face selection {p}: not valid JSON ({exc})") from None
    if isinstance(data, dict):
        data = data.get("faces")
    if not isinstance(data, list) or not all(isinstance(i, int) and not isinstance(i, bool)
                                             and i >= 0 for i in data):
        raise InputError(f"face selection {p}: expected a JSON list of non-negative face "
                         "indices")
    return np.asarray(data, dtype=np.int64)


def face_selection(path, V, F, *, color=None, tolerance: float = PAINT_TOLERANCE) -> np.ndarray:
    """The base faces a selection file selects: JSON indices or a painted PLY/OBJ.

    Parameters
    ----------
    path : str or os.PathLike
        ``.json`` (:func:`face_selection_file`), or ``.ply`` / ``.obj``
        with colours (:func:`painted_faces`).
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        The base, as read from its file (before any scaling).
    color : sequence of 3 floats, optional
        The paint colour (0..255); see :func:`painted_faces`.
    tolerance : float, optional
        Per-channel colour tolerance (0..255).

    Returns
    -------
    numpy.ndarray, (m,) bool

    Raises
    ------
    InputError
        Everything :func:`face_selection_file` and :func:`painted_faces`
        refuse, an index beyond the base's faces, other mesh formats, or
        ``color`` with a JSON file; messages start with "face selection".
    """
    p = Path(path)
    m = np.asarray(F).shape[0]
    if p.suffix.lower() in (".ply", ".obj"):
        return painted_faces(p, V, F, color=color, tolerance=tolerance)
    if p.suffix.lower() in _MESH_SUFFIXES:
        raise InputError(f"face selection {p}: painted selections are read from PLY (per-face "
                         "or per-vertex colours) and OBJ (v x y z r g b) files; export the "
                         "painted part as one of those")
    if color is not None:
        raise InputError(f"mask color applies to a painted PLY/OBJ selection, not to {p.name}")
    idx = face_selection_file(p)
    if idx.size and idx.max() >= m:
        raise InputError(f"face selection {p}: index {int(idx.max())}, but the base has {m} "
                         "faces")
    sel = np.zeros(m, dtype=bool)
    sel[idx] = True
    return sel


def _paint_color(color) -> np.ndarray | None:
    if color is None:
        return None
    try:
        vals = [finite_number(v, name="mask color") for v in color]
    except TypeError:
        vals = []
    if len(vals) != 3 or not all(0.0 <= v <= 255.0 for v in vals):
        raise InputError(f"mask color must be three numbers R,G,B in 0..255, got {color!r}")
    return np.asarray(vals, dtype=np.float64)


def _painted(rgb: np.ndarray, color, tol: float, where: str) -> np.ndarray:
    """Which of ``rgb`` (k, 3) are painted (see the module notes)."""
    if rgb.shape[0] == 0:
        raise InputError(f"face selection {where}: the painted mesh has no faces")
    if color is not None:
        on = np.abs(rgb - color).max(axis=1) <= tol
        if not on.any():
            q, cnt = np.unique(np.rint(rgb).astype(np.int64), axis=0, return_counts=True)
            top = ", ".join(",".join(map(str, q[i])) for i in np.argsort(-cnt, kind="stable")[:4])
            raise InputError(f"face selection {where}: no colour within {tol:g} of mask color "
                             f"{','.join(f'{v:g}' for v in color)}; the file's colours are "
                             f"{top}")
        return on
    q, inv, cnt = np.unique(np.rint(rgb).astype(np.int64), axis=0, return_inverse=True,
                            return_counts=True)
    order = np.argsort(-cnt, kind="stable")
    if q.shape[0] == 1:
        raise InputError(f"face selection {where}: every face has the same colour "
                         f"{','.join(map(str, q[0]))}: nothing is painted")
    if cnt[order[0]] == cnt[order[1]]:
        raise InputError(f"face selection {where}: colours {','.join(map(str, q[order[0]]))} "
                         f"and {','.join(map(str, q[order[1]]))} are equally common, so the "
                         "unpainted one is unknown; name the paint's colour (mask color R,G,B, "
                         "--mask-color in the command)")
    base = q[order[0]].astype(np.float64)
    on = np.abs(rgb - base).max(axis=1) > tol
    if not on.any():
        raise InputError(f"face selection {where}: every colour is within {tol:g} of the base "
                         f"colour {','.join(map(str, q[order[0]]))}: nothing is painted (lower "
                         "the mask tolerance, --mask-tolerance in the command)")
    return on


def painted_faces(path, V, F, *, color=None, tolerance: float = PAINT_TOLERANCE) -> np.ndarray:
    """The base faces painted in a coloured copy of the base (see the module notes).

    Parameters
    ----------
    path : str or os.PathLike
        A PLY with per-face or per-vertex colours (ASCII or binary), or an
        OBJ with ``v x y z r g b`` vertex colours (0..1 or 0..255).
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
        The base, in the painted file's units and placement.
    color : sequence of 3 floats, optional
        The paint (0..255): faces whose colour matches it are selected.
        Default: faces whose colour differs from the most common one.
    tolerance : float, optional
        Per-channel colour tolerance on 0..255 (default
        :data:`PAINT_TOLERANCE`).

    Returns
    -------
    numpy.ndarray, (m,) bool

    Raises
    ------
    InputError
        An unreadable file, no colours, a bad ``color`` or ``tolerance``,
        nothing painted (one colour only, or no face of ``color``), two
        equally common colours without ``color``, or a painted mesh that is
        not the base (nearest centroids farther than
        :data:`MAX_TRANSFER_DISTANCE` of the diagonal on average).  Messages
        start with "face selection" (or "mask color" / "mask tolerance").

    Examples
    --------
    >>> import tempfile, pathlib
    >>> from geotex.mesh.primitives import box
    >>> V, F = box()
    >>> rows = [" ".join(map(repr, v)) for v in V.tolist()]
    >>> paint = [f"3 {a} {b} {c} " + ("255 0 0" if i < 2 else "200 200 200")
    ...          for i, (a, b, c) in enumerate(F.tolist())]
    >>> head = ["ply", "format ascii 1.0", f"element vertex {len(V)}", "property double x",
    ...         "property double y", "property double z", f"element face {len(F)}",
    ...         "property list uchar int vertex_indices", "property uchar red",
    ...         "property uchar green", "property uchar blue", "end_header"]
    >>> tmp = tempfile.TemporaryDirectory()
    >>> p = pathlib.Path(tmp.name) / "painted.ply"
    >>> _ = p.write_text("\\n".join(head + rows + paint) + "\\n")
    >>> painted_faces(p, V, F).nonzero()[0].tolist()
    [0, 1]
    >>> tmp.cleanup()
    """
    p = Path(path)
    col = _paint_color(color)
    tol = finite_number(tolerance, name="mask tolerance")
    if not 0 <= tol <= 255:
        raise InputError(f"mask tolerance must be in [0, 255], got {tolerance!r}")
    V = np.asarray(V, dtype=np.float64)
    F = np.asarray(F, dtype=np.int64)
    try:
        mesh, face_rgb, vertex_rgb = read_mesh_colors(p)
    except GeotexError as exc:
        raise InputError(f"face selection {' '.join(str(exc).split())}") from None
    Vp, Fp = mesh.vertices, mesh.faces
    if face_rgb is None and vertex_rgb is None:
        raise InputError(f"face selection {p}: the file has no colours (PLY needs red green "
                         "blue properties on its face or vertex element, OBJ v x y z r g b "
                         "lines)")
    if Fp.shape[0] == 0:
        raise InputError(f"face selection {p}: the painted mesh has no faces")
    if face_rgb is not None:
        sel = _painted(face_rgb, col, tol, str(p))
    else:
        on = _painted(vertex_rgb, col, tol, str(p))
        sel = on[Fp].sum(axis=1) >= 2
        if not sel.any():
            raise InputError(f"face selection {p}: no face has two painted corners (paint "
                             "whole faces, or a wider stroke)")
    return _transferred(sel, Vp, Fp, V, F, p)


def _transferred(sel, Vp, Fp, V, F, p) -> np.ndarray:
    """The painted selection ``sel`` on (Vp, Fp) carried to the base (V, F)."""
    diag = float(np.linalg.norm(np.ptp(V, axis=0))) if V.shape[0] else 0.0
    Cb = V[F].mean(axis=1)
    Cp = Vp[Fp].mean(axis=1)
    if Cp.shape == Cb.shape and np.abs(Cp - Cb).max() <= 1e-6 * diag:
        return sel.copy()
    from scipy.spatial import cKDTree  # lazy: scipy.spatial is heavy for the CLI start

    dist, near = cKDTree(Cp).query(Cb, k=1)
    mean = float(dist.mean())
    if not mean <= MAX_TRANSFER_DISTANCE * diag:
        raise InputError(
            f"face selection {p}: the painted mesh is not the base ({Fp.shape[0]} faces; base "
            f"faces lie {mean:.3g} on average from the nearest painted face, "
            f"{100 * mean / diag if diag else float('inf'):.2g} % of the diagonal, above "
            f"{100 * MAX_TRANSFER_DISTANCE:g} %); paint the part itself, same units and "
            "placement")
    return sel[near]


def bucket_fill_faces(V, F, seeds, *, max_angle: float) -> np.ndarray:
    """Faces reached from ``seeds`` across edges with dihedral angle <= ``max_angle``.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    seeds : sequence of int
    max_angle : float
        Degrees.

    Returns
    -------
    numpy.ndarray, (m,) bool
    """

    m = F.shape[0]
    seeds = np.asarray(seeds, dtype=np.int64)
    if seeds.size and (seeds.min() < 0 or seeds.max() >= m):
        raise InputError(f"fill seed faces must be in [0, {m}), got {seeds.tolist()}")
    topo = edge_topology(F, V.shape[0])
    ef = topo.edge_faces()
    ok = (ef >= 0).all(axis=1)
    ef = ef[ok]
    Nf = face_normals(V, F)
    cosang = np.einsum("ij,ij->i", Nf[ef[:, 0]], Nf[ef[:, 1]])
    keep = cosang >= math.cos(math.radians(max_angle)) - 1e-12
    e = ef[keep]
    A = sp.coo_matrix((np.ones(e.shape[0]), (e[:, 0], e[:, 1])), shape=(m, m))
    _, lab = connected_components(A, directed=False)
    return np.isin(lab, np.unique(lab[seeds])) if seeds.size else np.zeros(m, dtype=bool)


def selected_faces(V, F, opt: MaskOptions) -> np.ndarray:
    """Base faces that get relief under ``opt``.

    Returns
    -------
    numpy.ndarray, (m,) bool
    """
    m = F.shape[0]
    Nf = face_normals(V, F)
    C = V[F].mean(axis=1)
    sel = np.zeros(m, dtype=bool)
    any_sel = False
    if opt.faces is not None:
        if opt.faces.size and opt.faces.max() >= m:
            raise InputError(f"face selection has index {int(opt.faces.max())}, but the mesh "
                             f"has {m} faces")
        sel[opt.faces] = True
        any_sel = True
    if opt.box is not None:
        b = np.asarray(opt.box)
        sel |= np.all((C >= b[:3]) & (C <= b[3:]), axis=1)
        any_sel = True
    if opt.sphere is not None:
        s = np.asarray(opt.sphere)
        sel |= np.linalg.norm(C - s[:3], axis=1) <= s[3]
        any_sel = True
    if opt.normal_cone is not None:
        d = np.asarray(opt.normal_cone[:3], dtype=np.float64)
        d /= np.linalg.norm(d)
        sel |= Nf @ d >= math.cos(math.radians(opt.normal_cone[3])) - 1e-12
        any_sel = True
    if opt.fill_seeds:
        sel |= bucket_fill_faces(V, F, opt.fill_seeds, max_angle=opt.fill_angle)
        any_sel = True
    if not any_sel:
        on = np.ones(m, dtype=bool)
    else:
        on = sel if opt.select_mode == "include" else ~sel
    if opt.bottom_angle > 0:
        on &= ~(Nf[:, 2] <= -math.cos(math.radians(opt.bottom_angle)) + 1e-12)
    if opt.top_angle > 0:
        on &= ~(Nf[:, 2] >= math.cos(math.radians(opt.top_angle)) - 1e-12)
    return on


def _curve(t: np.ndarray, curve: str) -> np.ndarray:
    if curve == "linear":
        return t
    if curve == "smoothstep":
        return t * t * (3 - 2 * t)
    return t * t                                   # ease-in


def mask_weights(points, faces_on: np.ndarray, *, width: float = 0.0,
                 curve: str = "smoothstep") -> np.ndarray | None:
    """Relief weight of every refined vertex from the base faces that get relief.

    Parameters
    ----------
    points : geotex.relief.ReliefPoints
    faces_on : numpy.ndarray, (m,) bool
        Per base face.
    width : float, optional
        Transition width (mm).
    curve : str, optional
        One of ``CURVES``.

    Returns
    -------
    numpy.ndarray, (p,) float64 or None
        ``None`` when every face gets relief (no mask).
    """
    if faces_on.all():
        return None
    n = points.positions.shape[0]
    held = np.zeros(n, dtype=bool)
    held[points.faces[~faces_on[points.parent]].ravel()] = True
    w = (~held).astype(np.float64)
    if width > 0 and held.any() and (~held).any():
        from scipy.spatial import cKDTree

        free = np.flatnonzero(~held)
        # the border: held vertices that touch a free one
        Fr = points.faces
        mixed = held[Fr].any(axis=1) & (~held[Fr]).any(axis=1)
        border = np.unique(Fr[mixed].ravel())
        border = border[held[border]]
        tree = cKDTree(points.positions[border])
        dist, _ = tree.query(points.positions[free], k=1, distance_upper_bound=width)
        t = np.clip(np.where(np.isfinite(dist), dist, width) / width, 0.0, 1.0)
        w[free] = _curve(t, curve)
    return w
