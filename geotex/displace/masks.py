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
* a face-selection file: a JSON list of face indices, or ``{"faces": [...]}``
  (the mesh readers drop per-face and per-vertex colours, so painted PLY/OBJ
  selections are not read);
* geometric: a box (face centroid inside), a sphere (centroid inside), a
  normal cone (normal within an angle of a direction);
* bucket fill: faces reached from seed faces across edges whose dihedral
  angle is at most a threshold.

``select_mode="include"`` textures only the selected faces,
``"exclude"`` everything but them; angle exclusions apply in both modes.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from geotex.errors import InputError
from geotex.mesh.geometry import face_normals
from geotex.mesh.topology import edge_topology
from geotex.options import finite_number

__all__ = ["MaskOptions", "mask_options", "selected_faces", "face_selection_file",
           "bucket_fill_faces", "mask_weights", "CURVES"]

CURVES = ("linear", "smoothstep", "ease-in")


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
    """Read a face-selection file: JSON list of face indices or ``{"faces": [...]}``.

    Returns
    -------
    numpy.ndarray, (k,) int64

    Raises
    ------
    InputError
        Missing file, not JSON, not a list of non-negative integers, or a
        mesh file (painted colours are not read by geotex's readers).
    """
    p = Path(path)
    if p.suffix.lower() in (".ply", ".obj", ".off", ".stl", ".3mf", ".glb"):
        raise InputError(f"{p}: painted selections in mesh files are not supported (the mesh "
                         "readers drop colours); give a JSON list of face indices")
    if not p.is_file():
        raise InputError(f"{p}: no such face-selection file")
    try:
        data = json.loads(p.read_text())
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"{p}: not valid JSON ({exc})") from None
    if isinstance(data, dict):
        data = data.get("faces")
    if not isinstance(data, list) or not all(isinstance(i, int) and not isinstance(i, bool)
                                             and i >= 0 for i in data):
        raise InputError(f"{p}: expected a JSON list of non-negative face indices")
    return np.asarray(data, dtype=np.int64)


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
