"""Offline HTML pages with an interactive 3D viewer (three.js) of a mesh.

A page holds everything it needs: the viewer script (three.js, its GLTF loader
and orbit controls, bundled by ``viewer/`` in the repository) and the model as
a base64 GLB, so it opens from ``file://`` with no server and no network.

The viewer bundle is built from the npm registry, not committed:
``npm --prefix viewer ci && npm --prefix viewer run build`` writes
``geotex/data/viewer/geotex-viewer.js`` (about 0.6 MB), which the package
then ships as package data.  The CI script and the documentation build run
that step.
"""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

import numpy as np

from geotex.errors import InputError, ToolNotFoundError
from geotex.io.atomic import atomic_output
from geotex.io.glb import write_glb
from geotex.mesh import Mesh

__all__ = ["viewer_bundle_path", "viewer_bundle", "viewer_element", "viewer_page",
           "write_viewer_page", "glb_bytes", "mesh_turned_y_up"]

BUILD_HINT = ("build it with `npm --prefix viewer ci && npm --prefix viewer run build` "
              "in the geotex source tree")


def viewer_bundle_path() -> Path:
    """Return the path of the viewer bundle inside the installed package.

    Returns
    -------
    pathlib.Path
        ``geotex/data/viewer/geotex-viewer.js`` (it may not exist; see
        :func:`viewer_bundle`).
    """
    return Path(__file__).resolve().parent / "data" / "viewer" / "geotex-viewer.js"


def viewer_bundle() -> str:
    """Return the viewer script (three.js bundle) as text.

    Returns
    -------
    str
        The minified script.

    Raises
    ------
    ToolNotFoundError
        If the bundle was not built (see the module notes).
    """
    path = viewer_bundle_path()
    try:
        text = path.read_text(encoding="utf-8")
    except OSError:
        raise ToolNotFoundError(f"the 3D viewer script {path} is missing; {BUILD_HINT}",
                                tool="geotex-viewer") from None
    # the script goes inside <script>...</script>: it must not close that element
    return text.replace("</script", "<\\/script")


def mesh_turned_y_up(mesh, *, up: str):
    """Return ``mesh`` turned so that its ``up`` axis points along +y (glTF's convention).

    Parameters
    ----------
    mesh : geotex.mesh.Mesh
    up : {"x", "y", "z"}
        The axis that points up in ``mesh``.  A z-up mesh is turned by
        ``(x, y, z) -> (x, z, -y)``, an x-up mesh by ``(x, y, z) -> (-y, x, z)``
        (proper rotations: faces keep their orientation); a y-up mesh is
        returned as it is.

    Returns
    -------
    geotex.mesh.Mesh
        A new record (the input is not modified); uv and texture are kept.

    Raises
    ------
    InputError
        If ``up`` is not ``"x"``, ``"y"`` or ``"z"``.
    """
    up = _up_name(up)
    V = mesh.vertices
    if up == "y":
        return mesh
    if up == "z":
        W = np.column_stack([V[:, 0], V[:, 2], -V[:, 1]])
    else:
        W = np.column_stack([-V[:, 1], V[:, 0], V[:, 2]])
    return mesh.replace(vertices=W)


def glb_bytes(mesh, *, up: str = "y") -> bytes:
    """Return ``mesh`` encoded as a y-up binary glTF file (textured when it has a texture).

    Parameters
    ----------
    mesh : geotex.mesh.Mesh
    up : {"x", "y", "z"}, optional
        The axis that points up in ``mesh``; the file is written y-up, as
        the glTF specification says (see :func:`mesh_turned_y_up`).

    Returns
    -------
    bytes

    Raises
    ------
    InputError
        If ``mesh`` is not a :class:`~geotex.mesh.Mesh`.
    MeshFileError
        If the coordinates do not fit glTF's float32.
    """
    if not isinstance(mesh, Mesh):
        raise InputError(f"mesh must be a geotex.mesh.Mesh, got {type(mesh).__name__}")
    buf = io.BytesIO()
    write_glb(buf, mesh_turned_y_up(mesh, up=up))
    return buf.getvalue()


def _up_name(up: str) -> str:
    if up not in ("x", "y", "z"):
        raise InputError(f"up must be 'x', 'y' (glTF's convention) or 'z', got {up!r}")
    return up


def viewer_element(glb: bytes, *, element_id: str, up: str = "y", height: str = "480px",
                   caption: str = "") -> str:
    """Return the HTML of one viewer (a div and its embedded base64 GLB).

    Parameters
    ----------
    glb : bytes
        A binary glTF file.
    element_id : str
        Unique id on the page (letters, digits, ``-`` and ``_``).
    up : {"x", "y", "z"}, optional
        Axis that points up in the model's coordinates (glTF is y-up; a
        z-up model is turned upright).
    height : str, optional
        CSS height of the viewer.
    caption : str, optional
        Text shown under the viewer.

    Returns
    -------
    str
        HTML to place in a page that also loads the viewer script.

    Raises
    ------
    InputError
        If ``element_id`` or ``up`` is invalid.
    """
    up = _up_name(up)
    if not element_id or not all(c.isalnum() or c in "-_" for c in element_id):
        raise InputError(f"element_id must be letters, digits, - or _, got {element_id!r}")
    data = base64.b64encode(glb).decode("ascii")
    cap = (f'<p class="geotex-viewer-caption">{html.escape(caption)}</p>' if caption else "")
    return (f'<div class="geotex-viewer" data-model="{element_id}-glb" data-up="{up}" '
            f'style="width:100%;height:{html.escape(height)};position:relative;'
            f'border:1px solid #ccd;border-radius:4px;overflow:hidden"></div>{cap}\n'
            f'<script type="application/octet-stream" id="{element_id}-glb">{data}</script>')


def viewer_page(glb: bytes, *, title: str, up: str = "y") -> str:
    """Return a complete offline HTML page showing one model.

    Parameters
    ----------
    glb : bytes
        A binary glTF file.
    title : str
        Page title and heading.
    up : {"x", "y", "z"}, optional
        Axis that points up in the model's coordinates.

    Returns
    -------
    str

    Raises
    ------
    InputError
        If ``up`` is invalid.
    ToolNotFoundError
        If the viewer bundle was not built.
    """
    element = viewer_element(glb, element_id="model", up=up, height="calc(100vh - 4.5em)",
                             caption="drag to turn, scroll to zoom, right-drag to pan")
    t = html.escape(title)
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{t}</title><meta name=\"viewport\" content=\"width=device-width\">"
            "<style>body{margin:0.5em 1em;font-family:sans-serif;color:#222}"
            "h1{font-size:1.1em;margin:0 0 0.4em}"
            ".geotex-viewer-caption{margin:0.3em 0;font-size:0.85em;color:#666}</style>"
            f"</head><body><h1>{t}</h1>\n{element}\n"
            f"<script>{viewer_bundle()}</script>\n</body></html>\n")


def write_viewer_page(mesh, path, *, title: str | None = None, up: str = "z") -> Path:
    """Write an offline HTML viewer page of ``mesh``.

    Parameters
    ----------
    mesh : geotex.mesh.Mesh
        The model; its texture is shown where it has one.
    path : str or os.PathLike
        Output ``.html`` file (written atomically).
    title : str, optional
        Page title (default: the mesh name or the file stem).
    up : {"x", "y", "z"}, optional
        Axis that points up in the mesh's coordinates (z for geotex's
        printable models, y for glTF files).

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    InputError
        If ``path`` does not end in ``.html`` or ``up`` is invalid.
    ToolNotFoundError
        If the viewer bundle was not built.
    """
    path = Path(path)
    if path.suffix.lower() not in (".html", ".htm"):
        raise InputError(f"{path}: viewer pages are HTML; use a .html file name")
    page = viewer_page(glb_bytes(mesh, up=up), title=title or mesh.name or path.stem)
    with atomic_output(path, "w") as fh:
        fh.write(page)
    return path
