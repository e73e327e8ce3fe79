"""Off-screen pictures of meshes with pyvista (VTK).

Pictures are rendered without a display: when no X display is available the
EGL render window is selected before VTK is loaded.  Output files are written
atomically.
"""

from __future__ import annotations

import atexit
import gc
import io
import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from geotex.errors import InputError
from geotex.io.atomic import atomic_output
from geotex.mesh.arrays import as_mesh_arrays
from geotex.mesh.geometry import face_areas, face_normals
from geotex.mesh.topology import concatenated

__all__ = ["render_mesh", "render_panels", "Panel", "labelled_parts", "labelled_panel", "UP_AXES", "offscreen_pyvista",
           "split_by_uv", "view_direction", "background_renderer"]

UP_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
DEFAULT_COLOR = "#d9c7a3"
HIGHLIGHT_COLORS = ("#e4202a", "#ff8c00", "#1f6fd6", "#2ca02c")


def offscreen_pyvista():
    """Import pyvista set up for off-screen rendering (EGL without a display, VTK logs off).

    Returns
    -------
    module
        The ``pyvista`` module with ``OFF_SCREEN`` set.
    """
    if not os.environ.get("DISPLAY"):
        os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")
    # lazy: pyvista/VTK take ~0.3 s to import (also the environment must be set first)
    import pyvista as pv
    pv.OFF_SCREEN = True
    try:
        from vtkmodules.vtkCommonCore import vtkLogger
        vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    except ImportError:  # pragma: no cover - older VTK
        pass
    return pv


def _no_collection_at_exit() -> None:
    """Worker set-up: freeze the objects out of the collector when the worker exits.

    The worker exits when its pool is shut down, and its shutdown otherwise
    walks every VTK and pyvista object in full collections (about 1 s CPU
    after a picture of ~370k faces, which the caller waits for in
    ``shutdown``).
    """
    atexit.register(gc.freeze)


def _load_renderer() -> None:
    offscreen_pyvista()
    import pyvista.plotting  # noqa: F401  (the part of pyvista a picture needs)


def background_renderer() -> ProcessPoolExecutor:
    """A worker process for pictures, started now and already loading pyvista.

    A picture of a large mesh takes seconds (loading VTK, drawing, supersampling);
    submitting :func:`render_panels` or :func:`render_mesh` to this pool draws it
    on another core while the caller goes on (writing and checking files), and
    the import cost is paid while the caller is still computing. The process is
    spawned (not forked), so it shares no threads or locks with the caller, and
    it skips the garbage collections of its interpreter's shutdown
    (:func:`gc.freeze` at exit): shutting the pool down takes 0.3 s instead of
    1.6 s at load 16 after a picture of ~370k faces.

    Returns
    -------
    concurrent.futures.ProcessPoolExecutor
        One worker; shut it down (or use it as a context manager) when done.
        ``submit(render_panels, panels, path, ...)`` returns a future whose
        ``result()`` is the written path or raises the render's error.
    """
    pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"),
                               initializer=_no_collection_at_exit)
    pool.submit(_load_renderer)
    return pool


def _polydata(pv, V, F):
    faces = np.hstack([np.full((F.shape[0], 1), 3, dtype=np.int64), F]).ravel()
    return pv.PolyData(V, faces)


class Panel:
    """One mesh (plus optional extras) in a picture.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    title : str, optional
        Caption drawn at the top of the panel; a line wider than the panel is
        broken between words.
    color : str, optional
        Surface colour (ignored when ``scalars`` is given).
    scalars : array_like, (n,) or (m,), optional
        Per-vertex or per-face values drawn with ``cmap``.
    cmap : str, optional
    highlight : dict of str -> array_like (k, 2) int64, optional
        Named edge sets (vertex index pairs) drawn as thick coloured lines, with
        a legend; used to show boundary or non-manifold edges.
    show_edges : bool, optional
        Draw the triangle wireframe.
    arrows : tuple of array_like ((k, 3), (k, 3)), optional
        Arrow origins and vectors (drawn at the given length), e.g. a
        tangent field at face centroids.
    markers : dict of str -> (array_like (k, 3), str), optional
        Named point sets drawn as spheres with a colour, with a legend; e.g.
        field singularities.
    uv : array_like, (n, 2) or (k, 2), optional
        Texture coordinates; with ``texture`` the surface shows the image
        (e.g. a checkerboard over a parameterization).  Per vertex (n rows)
        unless ``uv_faces`` is given.
    texture : numpy.ndarray, (h, w, 3 or 4) uint8, optional
        Image drawn with ``uv``; row 0 is the top of the image, ``v = 0`` its
        bottom (the convention of :class:`geotex.mesh.Mesh`).
    uv_faces : array_like, (m, 3) int64, optional
        Per-corner indices into ``uv`` (as read from OBJ or GLB files); a
        vertex used with several uv is drawn as several vertices.
    closeup : array_like (3,), optional
        Point to look at from close by, instead of the whole mesh.
    closeup_radius : float, optional
        Radius of the region shown around ``closeup`` (default: 12% of the
        bounding-box diagonal).
    inset : bool, optional
        With ``closeup``: draw a small picture of the whole object in the
        lower right corner of the panel, with a red circle marking the
        close-up point and its radius (default True).  The close-up region is
        framed beside it, clear of the inset and of the caption.

    Raises
    ------
    InputError
        If the arrays have the wrong shapes, ``uv`` and ``texture`` are not
        given together, or the close-up point or radius is not finite.
    """

    def __init__(self, V, F, *, title: str = "", color: str = DEFAULT_COLOR,
                 scalars=None, cmap: str = "viridis", highlight: dict | None = None,
                 show_edges: bool = False, arrows=None, markers: dict | None = None,
                 uv=None, texture=None, uv_faces=None, closeup=None,
                 closeup_radius: float | None = None, inset: bool = True):
        self.V, self.F = as_mesh_arrays(V, F)
        self.inset = bool(inset)
        self.title = title
        self.color = color
        self.scalars = None if scalars is None else np.asarray(scalars, dtype=np.float64)
        self.cmap = cmap
        self.highlight = highlight or {}
        self.show_edges = show_edges
        self.arrows = None
        if arrows is not None:
            P = np.asarray(arrows[0], dtype=np.float64).reshape(-1, 3)
            D = np.asarray(arrows[1], dtype=np.float64).reshape(-1, 3)
            if P.shape != D.shape:
                raise InputError("arrows need as many origins as vectors")
            self.arrows = (P, D)
        self.markers = {k: (np.asarray(p, dtype=np.float64).reshape(-1, 3), c)
                        for k, (p, c) in (markers or {}).items()}
        self.uv = None if uv is None else np.asarray(uv, dtype=np.float64)
        if (self.uv is None) != (texture is None):
            raise InputError("uv and texture must be given together")
        if uv_faces is not None:
            if self.uv is None:
                raise InputError("uv_faces needs uv and texture")
            self.V, self.F, self.uv = split_by_uv(self.V, self.F, self.uv, uv_faces)
        if self.uv is not None and self.uv.shape != (self.V.shape[0], 2):
            raise InputError(f"uv must have shape ({self.V.shape[0]}, 2), got {self.uv.shape}")
        self.texture = None if texture is None else np.ascontiguousarray(texture, dtype=np.uint8)
        if self.texture is not None and (self.texture.ndim != 3
                                         or self.texture.shape[2] not in (3, 4)):
            raise InputError("texture must be an (h, w, 3 or 4) uint8 image")
        self.closeup = None
        self.closeup_radius = None
        if closeup is not None:
            c = np.asarray(closeup, dtype=np.float64).reshape(-1)
            if c.shape != (3,) or not np.isfinite(c).all():
                raise InputError("closeup must be a finite point (x, y, z)")
            self.closeup = c
            if closeup_radius is not None:
                r = float(closeup_radius)
                if not np.isfinite(r) or r <= 0:
                    raise InputError(f"closeup radius must be a positive number, got {r}")
                self.closeup_radius = r


def labelled_parts(parts) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stack ``(V, F, label)`` parts into one mesh with a label per face.

    Parameters
    ----------
    parts : iterable of (V (n_i, 3) float64, F (m_i, 3) int64, label)
        ``label``: an int for the whole part or an (m_i,) int array. Parts
        without faces are skipped (:func:`geotex.mesh.topology.concatenated`).

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    labels : numpy.ndarray, (m,) int64
    """
    parts = [(V, F, lab) for V, F, lab in parts if len(F)]
    V, F = concatenated((V, F) for V, F, _ in parts)
    labels = [np.broadcast_to(np.asarray(lab, dtype=np.int64), (len(F_),)) for _, F_, lab in parts]
    return V, F, (np.concatenate(labels) if labels else np.zeros(0, dtype=np.int64))


def labelled_panel(V, F, labels, title: str = "", *, palette: dict) -> "Panel":
    """A panel whose faces are coloured by integer labels through ``palette``.

    Parameters
    ----------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64
    labels : numpy.ndarray, (m,) int
    title : str
    palette : dict of int -> str
        Colour of every label used.

    Returns
    -------
    Panel

    Raises
    ------
    InputError
        A label used by a face has no colour in ``palette``.
    """
    used = np.unique(np.asarray(labels, dtype=np.int64))
    missing = [int(u) for u in used if int(u) not in palette]
    if missing:
        raise InputError(f"labelled_panel: no colour for labels {missing}")
    return Panel(V, F, scalars=np.searchsorted(used, labels).astype(np.float64),
                 cmap=[palette[int(u)] for u in used], title=title)


def split_by_uv(V, F, uv, uv_faces) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return a mesh with one vertex per distinct (vertex, uv) corner pair.

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    uv : array_like, (k, 2) float64
        Texture coordinates.
    uv_faces : array_like, (m, 3) int64
        Per-corner indices into ``uv``.

    Returns
    -------
    V2 : numpy.ndarray, (p, 3) float64
        Positions; a vertex used with several uv appears once per uv.
    F2 : numpy.ndarray, (m, 3) int64
        The same triangles over ``V2``.
    uv2 : numpy.ndarray, (p, 2) float64
        One texture coordinate per vertex of ``V2``.

    Raises
    ------
    InputError
        If ``uv_faces`` does not have one row per face or indexes outside ``uv``.
    """
    V, F = as_mesh_arrays(V, F)
    uv = np.asarray(uv, dtype=np.float64).reshape(-1, 2)
    FT = np.asarray(uv_faces, dtype=np.int64)
    if FT.shape != F.shape:
        raise InputError(f"uv_faces must have shape {F.shape}, got {FT.shape}")
    if FT.size and (FT.min() < 0 or FT.max() >= uv.shape[0]):
        raise InputError("uv_faces indexes outside uv")
    pairs = np.stack([F.ravel(), FT.ravel()], axis=1)
    unique, inverse = np.unique(pairs, axis=0, return_inverse=True)
    return V[unique[:, 0]], inverse.reshape(-1, 3).astype(np.int64), uv[unique[:, 1]]


def _up_vector(up) -> np.ndarray:
    if isinstance(up, str):
        if up.lower() not in UP_AXES:
            raise InputError(f"up must be one of x, y, z or a vector, got {up!r}")
        return np.array(UP_AXES[up.lower()])
    v = np.asarray(up, dtype=np.float64).reshape(3)
    if not np.isfinite(v).all() or np.linalg.norm(v) == 0:
        raise InputError("up must be a non-zero finite vector")
    return v / np.linalg.norm(v)


def view_direction(up) -> np.ndarray:
    """Return the unit direction from the object to the camera of the default view.

    The view is the front three-quarter view, from the front-right and above
    (elevation about 25 degrees), so the underside is never shown.  "Front"
    is the side facing -y for a z-up picture and +z for a y-up or x-up one
    (the usual front of models in those conventions).

    Parameters
    ----------
    up : {"x", "y", "z"} or array_like (3,)
        World direction that points up in the picture.

    Returns
    -------
    numpy.ndarray, (3,) float64

    Raises
    ------
    InputError
        If ``up`` is not an axis name or a non-zero finite vector.
    """
    up = _up_vector(up)
    helper = np.array([0.0, 0.0, 1.0]) if abs(up[2]) < 0.9 else np.array([0.0, -1.0, 0.0])
    front = helper - up * (helper @ up)
    front /= np.linalg.norm(front)
    right = np.cross(up, front)
    direction = front * 1.0 + right * 0.75 + up * 0.58
    return direction / np.linalg.norm(direction)


_VIEW_ANGLE = 30.0          # VTK's default vertical view angle, degrees


def _fit_camera(P: np.ndarray, direction: np.ndarray, up: np.ndarray, aspect: float,
                margin: float = 1.1, top: float = 0.0, bottom: float = 0.0):
    """Camera looking along -direction at points P, as close as keeps all in view.

    ``top`` and ``bottom`` are the fractions of the picture's height kept free
    (for the caption and the legend): the points fit in the band between.
    """
    right = np.cross(direction, up)
    right /= np.linalg.norm(right)
    vup = np.cross(right, direction)
    center = 0.5 * (P.min(axis=0) + P.max(axis=0))
    Q = P - center
    xr, xu = Q @ right, Q @ vup
    center = center + right * 0.5 * (xr.min() + xr.max()) + vup * 0.5 * (xu.min() + xu.max())
    Q = P - center
    xr, xu, xd = Q @ right, Q @ vup, Q @ direction
    t = np.tan(np.radians(_VIEW_ANGLE) / 2)
    top, bottom = min(max(top, 0.0), 0.4), min(max(bottom, 0.0), 0.3)
    band = 1.0 - top - bottom                     # free height, as a fraction
    tv = t * band / margin
    th = t * aspect / margin
    dist = float(np.max(np.maximum(xd + np.abs(xr) / th, xd + np.abs(xu) / tv)))
    size = float(np.linalg.norm(np.ptp(P, axis=0))) or 1.0
    dist = max(dist, 1e-3 * size)
    # move the camera so that the band's middle is the picture's middle (a
    # translation; the view direction is unchanged)
    shift = vup * (top - bottom) * dist * t
    return [tuple(center + direction * dist + shift), tuple(center + shift), tuple(vup)]


def _closeup_radius(V, radius) -> float:
    diag = float(np.linalg.norm(np.ptp(V, axis=0))) or 1.0
    return 0.12 * diag if radius is None else float(radius)


def _local_normal(V, F, point, r) -> np.ndarray:
    """Area-weighted unit normal of the faces within ``r`` of ``point`` (zero if none)."""
    if not F.shape[0]:
        return np.zeros(3)
    C = V[F].mean(axis=1)
    dist_c = np.linalg.norm(C - point, axis=1)
    near = dist_c <= r
    if not near.any():
        near = dist_c == dist_c.min()
    n = (face_normals(V, F[near]) * face_areas(V, F[near])[:, None]).sum(axis=0)
    length = np.linalg.norm(n)
    return n / length if length > 0 else np.zeros(3)


#: width of a close-up's inset as a fraction of the panel's width, and its margin
INSET_FRACTION = 0.28
_INSET_MARGIN = 0.015


def _closeup_region(aspect: float, top: float, bottom: float, inset: bool):
    """Where in the panel a close-up's region goes: centre and radius.

    The region is a disc in the part of the panel that the caption band
    (``top``), the legend (``bottom``) and the inset (lower right corner, when
    ``inset``) leave free: the largest disc of the free rectangle left of the
    inset or of the one above it.

    Returns ``(cx, cy, radius)``: the centre in panel fractions (x from the
    left, y from the bottom) and the radius as a fraction of the panel height.
    """
    y1 = 1.0 - top
    rects = [(0.0, bottom, 1.0, y1)]
    if inset:
        # the inset has the panel's aspect; its margin is a fraction of the width
        sx = INSET_FRACTION + 2 * _INSET_MARGIN
        sy = INSET_FRACTION + 2 * _INSET_MARGIN * aspect
        rects = [(0.0, bottom, 1.0 - sx, y1), (0.0, max(bottom, sy), 1.0, y1)]
    best = max(rects, key=lambda q: min((q[2] - q[0]) * aspect, q[3] - q[1]))
    x0, y0, x1, y1 = best
    radius = 0.5 * min((x1 - x0) * aspect, y1 - y0)
    return 0.5 * (x0 + x1), 0.5 * (y0 + y1), max(radius, 0.05)


def _closeup_camera(V, F, point, radius, up, aspect, top: float = 0.0, bottom: float = 0.0,
                    inset: bool = False):
    """Camera looking at ``point`` from outside, along the local surface normal.

    ``top`` is the fraction of the picture's height covered by the caption
    band and ``bottom`` the one of the legend; with ``inset`` the lower right
    corner holds the inset.  The region of ``radius`` around the point fills
    the largest disc of what they leave free (:func:`_closeup_region`).
    """
    r = _closeup_radius(V, radius)
    default = view_direction(up)
    direction = default
    n = _local_normal(V, F, point, r)
    if np.linalg.norm(n) > 0:
        # the local outward normal, bent toward the default view so the relief
        # is lit from the side
        d = n + 0.35 * default
        if np.linalg.norm(d) > 0:
            direction = d / np.linalg.norm(d)
    view = -direction
    right = np.cross(view, up)
    if np.linalg.norm(right) < 1e-6:            # looking straight down or up
        right = np.cross(-default, up)
    right /= np.linalg.norm(right)             # points to the right in the picture
    vup = np.cross(right, view)
    t = np.tan(np.radians(_VIEW_ANGLE) / 2)
    top = min(max(top, 0.0), 0.4)
    bottom = min(max(bottom, 0.0), 0.3)
    cx, cy, rh = _closeup_region(aspect, top, bottom, inset)
    dist = r / (2.0 * rh * t)
    # a translation: the point shows at (cx, cy) of the panel, not in its middle
    shift = -(right * (cx - 0.5) * 2.0 * aspect + vup * (cy - 0.5) * 2.0) * dist * t
    return [tuple(point + direction * dist + shift), tuple(point + shift), tuple(vup)]


def _inset_direction(V, F, point, radius, up) -> np.ndarray:
    """View direction of a close-up's inset: the default view, unless it sees the point's back.

    When the surface at the point faces away from the default view (e.g. a
    point on the back of the model), the inset looks from the point's side
    instead: the default view turned about the up axis toward the local
    normal, at the same elevation.
    """
    default = view_direction(up)
    n = _local_normal(V, F, point, _closeup_radius(V, radius))
    if n @ default >= 0.1:
        return default
    h = n - up * (n @ up)
    d_h = default - up * (default @ up)
    if np.linalg.norm(h) < 1e-6:                # facing straight down: the default view
        return default
    d = h / np.linalg.norm(h) * np.linalg.norm(d_h) + up * (default @ up)
    return d / np.linalg.norm(d)


def _project(camera, P, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Pixel positions (column, row) and depths of points P seen by a perspective camera."""
    pos, focal, vup = (np.asarray(c, dtype=np.float64) for c in camera)
    view = focal - pos
    view /= np.linalg.norm(view)
    right = np.cross(view, vup)
    right /= np.linalg.norm(right)
    upv = np.cross(right, view)
    Q = np.atleast_2d(P) - pos
    depth = Q @ view
    t = np.tan(np.radians(_VIEW_ANGLE) / 2)
    half = 0.5 * height
    scale = half / (np.maximum(depth, 1e-12) * t)
    return np.column_stack([0.5 * width + (Q @ right) * scale,
                            half - (Q @ upv) * scale]), depth


#: colour of the caption band of a close-up: the top colour of the background
CAPTION_BAND = "#dfe6ee"


def _caption_band(pv, plotter, top: float) -> None:
    """Cover the top ``top`` of the current panel with an opaque band (under its caption).

    A close-up's surface fills the whole panel; the band keeps the caption
    readable, on the same colour as the other panels' captions, with a thin
    line at its lower edge.
    """
    # lazy: VTK's 2D classes load with pyvista (see offscreen_pyvista)
    from vtkmodules.vtkRenderingCore import vtkActor2D, vtkCoordinate, vtkPolyDataMapper2D

    y0 = 1.0 - top
    band = pv.PolyData(np.array([[0.0, y0, 0.0], [1.0, y0, 0.0], [1.0, 1.0, 0.0],
                                 [0.0, 1.0, 0.0]]), faces=np.array([4, 0, 1, 2, 3]))
    edge = pv.PolyData(np.array([[0.0, y0, 0.0], [1.0, y0, 0.0]]), lines=np.array([2, 0, 1]))
    for poly, color, width in ((band, CAPTION_BAND, 1.0), (edge, "#9aa6b2", 1.5)):
        coordinate = vtkCoordinate()
        coordinate.SetCoordinateSystemToNormalizedViewport()
        mapper = vtkPolyDataMapper2D()
        mapper.SetInputData(poly)
        mapper.SetTransformCoordinate(coordinate)
        actor = vtkActor2D()
        actor.SetMapper(mapper)
        actor.GetProperty().SetColor(pv.Color(color).float_rgb)
        actor.GetProperty().SetLineWidth(width)
        plotter.renderer.AddViewProp(actor)


def _add_surface(pv, plotter, panel: Panel) -> None:
    """The panel's surface (textured, coloured by scalars or plain) or its points."""
    V, F = panel.V, panel.F
    if F.shape[0]:
        poly = _polydata(pv, V, F)
        kwargs = dict(smooth_shading=False, specular=0.25, specular_power=20,
                      show_edges=panel.show_edges, edge_color="#555555", line_width=0.5)
        if panel.texture is not None:
            poly.active_texture_coordinates = panel.uv
            kwargs["specular"] = 0.1
            plotter.add_mesh(poly, texture=pv.Texture(panel.texture), **kwargs)
        elif panel.scalars is not None:
            plotter.add_mesh(poly, scalars=panel.scalars, cmap=panel.cmap,
                             show_scalar_bar=False, **kwargs)
        else:
            plotter.add_mesh(poly, color=panel.color, **kwargs)
    elif V.shape[0]:
        plotter.add_points(V, color=panel.color, point_size=4)


#: size (VTK points at 72 dpi) of the panel captions as drawn: pyvista's caption
#: (a corner annotation at font_size 12) settles at this size whatever the panel size
#: (measured on panels 300 to 1200 pixels wide)
_TITLE_POINTS = 30
#: pixels kept free on each side of a caption line
_TITLE_MARGIN = 8


def _wrapped_title(title: str, width: int) -> str:
    """``title`` with line breaks between words so that every line fits ``width`` pixels.

    Lines are measured with VTK's own text renderer (the font the caption is
    drawn in); a single word wider than the panel stays on its own line.  A
    broken line is balanced: as few lines as fit, each as short as that number
    of lines allows (no single word left alone on the last line).
    """
    # lazy: VTK's text classes load with pyvista (see offscreen_pyvista)
    import vtkmodules.vtkRenderingFreeType  # noqa: F401 - the text renderer's implementation
    from vtkmodules.vtkRenderingCore import vtkTextProperty, vtkTextRenderer

    renderer = vtkTextRenderer()
    prop = vtkTextProperty()
    prop.SetFontFamilyToArial()
    prop.SetFontSize(_TITLE_POINTS)
    box = [0, 0, 0, 0]

    def text_width(text: str) -> int:
        renderer.GetBoundingBox(prop, text, box, 72)
        return box[1] - box[0] + 1

    def greedy(words: list[str], room: int) -> list[str]:
        lines, current = [], words[0]
        for word in words[1:]:
            if text_width(f"{current} {word}") <= room:
                current = f"{current} {word}"
            else:
                lines.append(current)
                current = word
        return lines + [current]

    room = width - 2 * _TITLE_MARGIN
    out = []
    for line in title.split("\n"):
        words = line.split(" ")
        lines = greedy(words, room)
        if len(lines) > 1:
            # the narrowest room that still needs no more lines (bisection)
            low, high = 0, room
            while high - low > 2:
                middle = (low + high) // 2
                if len(greedy(words, middle)) <= len(lines):
                    high = middle
                else:
                    low = middle
            lines = greedy(words, high)
        out.extend(lines)
    return "\n".join(out)


def _draw(pv, plotter, panel: Panel, up: np.ndarray, aspect: float, width: int):
    V, F = panel.V, panel.F
    _add_surface(pv, plotter, panel)
    legend = []
    diag = float(np.linalg.norm(np.ptp(V, axis=0))) if V.shape[0] else 1.0
    if panel.arrows is not None and panel.arrows[0].shape[0]:
        P, D = panel.arrows
        glyphs = pv.PolyData(P)
        glyphs["vectors"] = D
        length = np.linalg.norm(D, axis=1)
        glyphs["length"] = length
        arrow = pv.Arrow(tip_length=0.35, tip_radius=0.12, shaft_radius=0.035)
        plotter.add_mesh(glyphs.glyph(orient="vectors", scale="length", factor=1.0, geom=arrow),
                         color="#1d3f8f")
    for label, (P, color) in panel.markers.items():
        if P.shape[0] == 0:
            continue
        balls = pv.PolyData(P).glyph(geom=pv.Sphere(radius=diag * 0.012), scale=False,
                                     orient=False)
        plotter.add_mesh(balls, color=color, smooth_shading=True)
        legend.append([f"{label} ({P.shape[0]})", color])
    for (label, edges), color in zip(panel.highlight.items(), HIGHLIGHT_COLORS):
        E = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
        if E.shape[0] == 0:
            continue
        lines = np.hstack([np.full((E.shape[0], 1), 2, dtype=np.int64), E]).ravel()
        plotter.add_mesh(pv.PolyData(V, lines=lines), color=color, line_width=4,
                         render_lines_as_tubes=True)
        legend.append([f"{label} ({E.shape[0]})", color])
    if legend:
        # VTK fits the text to the box: a box as wide as the longest label
        # needs at a legible size (about 0.026 of a square panel per
        # character, 0.09 per line) keeps it so
        longest = max(len(text) for text, _ in legend)
        plotter.add_legend(legend, bcolor="white", face="line", loc="lower left",
                           size=(min(0.9, max(0.45, 0.026 * longest / aspect)),
                                 0.09 * len(legend)))
    title = _wrapped_title(panel.title, width) if panel.title else ""
    lines = title.count("\n") + 1 if title else 0
    top = (lines * 26.0 + 8.0) / plotter.window_size[1] if lines else 0.0
    closeup = panel.closeup is not None and V.shape[0] > 0
    if closeup and top:
        top += 8.0 / plotter.window_size[1]      # a little air under the last line
        _caption_band(pv, plotter, top)          # under the caption, drawn before it
    if title:
        plotter.add_text(title, position="upper_edge", font_size=12, color="#222222")
    if V.shape[0]:
        if closeup:
            plotter.camera_position = _closeup_camera(
                V, F, panel.closeup, panel.closeup_radius, up, aspect, top=top,
                bottom=0.07 * len(legend) + 0.02 if legend else 0.0, inset=panel.inset)
        else:
            # fit the mesh's own points (not its bounding sphere): it fills the panel
            plotter.camera_position = _fit_camera(
                V, view_direction(up), up, aspect, top=top,
                bottom=0.07 * len(legend) + 0.02 if legend else 0.0)
        plotter.reset_camera_clipping_range()


def render_panels(panels: list[Panel], path, *, size=(1200, 900), up="z") -> Path:
    """Render panels side by side into one PNG picture.

    Parameters
    ----------
    panels : list of Panel
        Drawn left to right, each with its own camera fitted to it.
    path : str or os.PathLike
        Output PNG file (written atomically).
    size : tuple of int, optional
        Width and height of each panel in pixels.
    up : {"x", "y", "z"} or array_like (3,), optional
        World direction that points up in the picture.

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    InputError
        On an empty panel list, a bad ``up`` or a non-PNG path.
    """
    path = Path(path)
    if path.suffix.lower() != ".png":
        raise InputError(f"{path}: pictures are written as PNG; use a .png file name")
    if not panels:
        raise InputError("nothing to render: no panels given")
    upv = _up_vector(up)
    pv = offscreen_pyvista()
    w, h = int(size[0]), int(size[1])
    plotter = pv.Plotter(off_screen=True, shape=(1, len(panels)),
                         window_size=(w * len(panels), h), border=False)
    try:
        for i, panel in enumerate(panels):
            plotter.subplot(0, i)
            plotter.set_background("white", top="#dfe6ee")
            plotter.enable_lightkit()
            _draw(pv, plotter, panel, upv, w / h, w)
        plotter.enable_anti_aliasing("ssaa", all_renderers=True)
        image = plotter.screenshot(return_img=True)
    finally:
        plotter.close()
    with_inset = [i for i, p in enumerate(panels)
                  if p.closeup is not None and p.inset and p.V.shape[0]]
    if with_inset:
        image = np.array(image, copy=True)
        iw = max(int(round(INSET_FRACTION * w)), 8)
        ih = max(int(round(iw * h / w)), 8)
        insets = _render_insets(pv, [panels[i] for i in with_inset], upv, iw, ih)
        margin = int(round(_INSET_MARGIN * w))
        for i, inset in zip(with_inset, insets):
            x0, y0 = (i + 1) * w - margin - iw, h - margin - ih
            image[y0:y0 + ih, x0:x0 + iw] = inset
    buf = io.BytesIO()
    Image.fromarray(np.asarray(image)).save(buf, format="PNG")
    with atomic_output(path, "wb") as fh:
        fh.write(buf.getvalue())
    return path


#: colour of the circle marking a close-up in its inset, and of the inset's frame
INSET_MARKER = "#e4202a"
INSET_FRAME = "#6b7785"


def _render_insets(pv, panels: list[Panel], up: np.ndarray, width: int,
                   height: int) -> list[np.ndarray]:
    """Pictures of the whole objects of close-up panels, each with its close-up marked.

    One small picture per panel (``height`` x ``width`` RGB): the whole mesh from
    the default view (or from the close-up's side, see :func:`_inset_direction`),
    a red circle of the close-up radius around the close-up point and a frame.
    """
    plotter = pv.Plotter(off_screen=True, shape=(1, len(panels)),
                         window_size=(width * len(panels), height), border=False)
    cameras = []
    try:
        for i, panel in enumerate(panels):
            plotter.subplot(0, i)
            plotter.set_background("white")
            plotter.enable_lightkit()
            _add_surface(pv, plotter, panel)
            direction = _inset_direction(panel.V, panel.F, panel.closeup,
                                         panel.closeup_radius, up)
            camera = _fit_camera(panel.V, direction, up, width / height, margin=1.12)
            plotter.camera_position = camera
            plotter.reset_camera_clipping_range()
            cameras.append(camera)
        plotter.enable_anti_aliasing("ssaa", all_renderers=True)
        image = np.asarray(plotter.screenshot(return_img=True))
    finally:
        plotter.close()
    line = max(2, int(round(width / 110)))
    out = []
    for i, (panel, camera) in enumerate(zip(panels, cameras)):
        picture = Image.fromarray(np.ascontiguousarray(image[:, i * width:(i + 1) * width, :3]))
        draw = ImageDraw.Draw(picture)
        r = _closeup_radius(panel.V, panel.closeup_radius)
        (c,), (depth,) = _project(camera, panel.closeup, width, height)
        t = np.tan(np.radians(_VIEW_ANGLE) / 2)
        rp = max(r / (max(depth, 1e-12) * t) * 0.5 * height, 2.5 * line)
        # a white halo under the red circle and dot: visible on dark and red surfaces
        for color, grow in (("white", 1), (INSET_MARKER, 0)):
            draw.ellipse([c[0] - rp - grow, c[1] - rp - grow, c[0] + rp + grow,
                          c[1] + rp + grow], outline=color, width=line + 2 * grow)
            dot = 1.2 * line + grow
            draw.ellipse([c[0] - dot, c[1] - dot, c[0] + dot, c[1] + dot], fill=color)
        draw.rectangle([0, 0, width - 1, height - 1], outline=INSET_FRAME,
                       width=max(1, line // 2 + 1))
        out.append(np.asarray(picture))
    return out


def render_mesh(V, F, path, *, size=(1200, 900), up="z", title: str = "",
                color: str = DEFAULT_COLOR, scalars=None, cmap: str = "viridis",
                highlight: dict | None = None, show_edges: bool = False,
                uv=None, uv_faces=None, texture=None, closeup=None,
                closeup_radius: float | None = None, inset: bool = True) -> Path:
    """Render one mesh off-screen into a PNG picture.

    The default camera shows the front three-quarter view from above (see
    :func:`view_direction`) and fits the mesh to the picture; ``closeup``
    looks at one point from outside instead, with an inset of the whole
    object marking where (``inset``).

    Parameters
    ----------
    V : array_like, (n, 3) float64
    F : array_like, (m, 3) int64
    path : str or os.PathLike
        Output PNG file.
    size : tuple of int, optional
        Picture width and height in pixels.
    up : {"x", "y", "z"} or array_like (3,), optional
        World direction that points up in the picture.
    title, color, scalars, cmap, highlight, show_edges
        See :class:`Panel`.
    uv, uv_faces, texture, closeup, closeup_radius, inset
        See :class:`Panel`.

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    InputError
        On a bad ``up``, a non-PNG path or inconsistent arrays.

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    >>> F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> # skipped in doctests: writes tet.png and needs an OpenGL context
    >>> render_mesh(V, F, "tet.png")  # doctest: +SKIP
    """
    panel = Panel(V, F, title=title, color=color, scalars=scalars, cmap=cmap,
                  highlight=highlight, show_edges=show_edges, uv=uv, uv_faces=uv_faces,
                  texture=texture, closeup=closeup, closeup_radius=closeup_radius,
                  inset=inset)
    return render_panels([panel], path, size=size, up=up)
