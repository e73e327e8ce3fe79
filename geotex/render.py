"""Off-screen pictures of meshes with pyvista (VTK).

Pictures are rendered without a display: when no X display is available the
EGL render window is selected before VTK is loaded.  Output files are written
atomically.
"""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np

from geotex.errors import InputError
from geotex.mesh.arrays import as_mesh_arrays

__all__ = ["render_mesh", "render_panels", "Panel", "UP_AXES", "offscreen_pyvista"]

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
    import pyvista as pv
    pv.OFF_SCREEN = True
    try:
        from vtkmodules.vtkCommonCore import vtkLogger
        vtkLogger.SetStderrVerbosity(vtkLogger.VERBOSITY_OFF)
    except ImportError:  # pragma: no cover - older VTK
        pass
    return pv


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
        Caption drawn at the top of the panel.
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
    uv : array_like, (n, 2), optional
        Per-vertex texture coordinates; with ``texture`` the surface shows
        the image (e.g. a checkerboard over a parameterization).
    texture : numpy.ndarray, (h, w, 3) uint8, optional
    """

    def __init__(self, V, F, *, title: str = "", color: str = DEFAULT_COLOR,
                 scalars=None, cmap: str = "viridis", highlight: dict | None = None,
                 show_edges: bool = False, arrows=None, markers: dict | None = None,
                 uv=None, texture=None):
        self.V, self.F = as_mesh_arrays(V, F)
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
        if self.uv is not None and self.uv.shape != (self.V.shape[0], 2):
            raise InputError(f"uv must have shape ({self.V.shape[0]}, 2), got {self.uv.shape}")
        if (self.uv is None) != (texture is None):
            raise InputError("uv and texture must be given together")
        self.texture = None if texture is None else np.ascontiguousarray(texture, dtype=np.uint8)


def _up_vector(up) -> np.ndarray:
    if isinstance(up, str):
        if up.lower() not in UP_AXES:
            raise InputError(f"up must be one of x, y, z or a vector, got {up!r}")
        return np.array(UP_AXES[up.lower()])
    v = np.asarray(up, dtype=np.float64).reshape(3)
    if not np.isfinite(v).all() or np.linalg.norm(v) == 0:
        raise InputError("up must be a non-zero finite vector")
    return v / np.linalg.norm(v)


def _camera(V: np.ndarray, up: np.ndarray):
    lo, hi = V.min(axis=0), V.max(axis=0)
    center = 0.5 * (lo + hi)
    radius = 0.5 * float(np.linalg.norm(hi - lo)) or 1.0
    # a three-quarter view from the front-right, slightly above
    helper = np.array([0.0, 0.0, 1.0]) if abs(up[2]) < 0.9 else np.array([0.0, -1.0, 0.0])
    front = helper - up * (helper @ up)
    front /= np.linalg.norm(front)
    right = np.cross(up, front)
    direction = front * 1.0 + right * 0.75 + up * 0.55
    direction /= np.linalg.norm(direction)
    position = center + direction * radius * 3.2
    return [tuple(position), tuple(center), tuple(up)]


def _draw(pv, plotter, panel: Panel, up: np.ndarray):
    V, F = panel.V, panel.F
    if F.shape[0]:
        poly = _polydata(pv, V, F)
        kwargs = dict(smooth_shading=False, specular=0.25, specular_power=20,
                      show_edges=panel.show_edges, edge_color="#555555", line_width=0.5)
        if panel.texture is not None:
            poly.active_texture_coordinates = panel.uv
            plotter.add_mesh(poly, texture=pv.Texture(panel.texture), **kwargs)
        elif panel.scalars is not None:
            plotter.add_mesh(poly, scalars=panel.scalars, cmap=panel.cmap,
                             show_scalar_bar=False, **kwargs)
        else:
            plotter.add_mesh(poly, color=panel.color, **kwargs)
    elif V.shape[0]:
        plotter.add_points(V, color=panel.color, point_size=4)
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
        plotter.add_legend(legend, bcolor="white", face="line", loc="lower left",
                           size=(0.45, 0.07 * len(legend)))
    if panel.title:
        plotter.add_text(panel.title, position="upper_edge", font_size=12, color="#222222")
    if V.shape[0]:
        plotter.camera_position = _camera(V, up)
        plotter.reset_camera()            # keep the view direction, fit the whole mesh
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
    from PIL import Image

    from geotex.io.atomic import atomic_output

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
            _draw(pv, plotter, panel, upv)
        plotter.enable_anti_aliasing("ssaa", all_renderers=True)
        image = plotter.screenshot(return_img=True)
    finally:
        plotter.close()
    buf = io.BytesIO()
    Image.fromarray(np.asarray(image)).save(buf, format="PNG")
    with atomic_output(path, "wb") as fh:
        fh.write(buf.getvalue())
    return path


def render_mesh(V, F, path, *, size=(1200, 900), up="z", title: str = "",
                color: str = DEFAULT_COLOR, scalars=None, cmap: str = "viridis",
                highlight: dict | None = None, show_edges: bool = False) -> Path:
    """Render one mesh off-screen into a PNG picture.

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

    Returns
    -------
    pathlib.Path

    Examples
    --------
    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    >>> F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> # skipped in doctests: writes tet.png and needs an OpenGL context
    >>> render_mesh(V, F, "tet.png")  # doctest: +SKIP
    """
    panel = Panel(V, F, title=title, color=color, scalars=scalars, cmap=cmap,
                  highlight=highlight, show_edges=show_edges)
    return render_panels([panel], path, size=size, up=up)
