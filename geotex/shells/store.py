"""Shell files (``.npz``): arrays plus a JSON metadata string, byte-reproducible.

Written as a deflate-compressed zip of ``.npy`` members with a fixed member
order and fixed timestamps, so the same shell always gives the same bytes.
Positions and offset directions stay float64; the quad data is integral
(exact), indices are int32. What can be recomputed exactly (the triangle
sub-grid and the quad edges) is not stored.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from geotex.errors import GeotexError, InputError, MeshFileError
from geotex.io.records import read_record, write_record
from geotex.param.polycube import PolyCube, PolyCubeDiagnostics
from geotex.param.polycube_quads import QuadLayout
from geotex.param.polycube_surface import subdivided_quads
from geotex.shells.build import Shell
from geotex.version import VERSION

__all__ = ["save_shell", "load_shell", "shell_metadata", "shell_file_metadata", "FORMAT"]

FORMAT = "geotex-shell-2"

#: stored arrays: name -> dtype. The sub-grid (P, F, quad grid) and the quad edges
#: are recomputed from the quad corners and labels when a shell is loaded.
_ARRAYS = {
    "origin": np.float64, "quad_corners": np.int32, "quad_label": np.int8, "Y": np.float64,
    "D": np.float64, "quad_folded": np.bool_, "base_vertices": np.float64,
    "base_faces": np.int32,
}
_DATE = (2020, 1, 1, 0, 0, 0)
_HINT = "rebuild it with 'geotex shell build'"


def _arrays_of(shell: Shell) -> dict:
    pc = shell.polycube
    return {"origin": pc.origin, "quad_corners": pc.layout.quad_corners,
            "quad_label": pc.layout.quad_label,
            "Y": pc.Y, "D": shell.D, "quad_folded": pc.quad_folded,
            "base_vertices": shell.base_vertices, "base_faces": shell.base_faces}


def shell_metadata(shell: Shell) -> dict:
    """The JSON metadata stored with a shell."""

    pc, diag = shell.polycube, shell.polycube.diagnostics
    return {
        "format": FORMAT, "name": shell.name, "tile_size": pc.tile_size, "res": pc.res,
        "vertices": int(pc.Y.shape[0]), "faces": int(pc.F.shape[0]),
        "base_vertices": int(shell.base_vertices.shape[0]),
        "base_faces": int(shell.base_faces.shape[0]), "quads": pc.layout.n_quads,
        "folded_quads": int(pc.quad_folded.sum()), "edges": pc.layout.n_edges,
        "max_height": shell.max_height,
        "distortion": {k: float(v) for k, v in diag.distortion.items()},
        "coverage": {k: float(v) for k, v in diag.coverage.items()},
        "voxels": diag.voxels, "tile_search": diag.tile_search, "source": shell.source,
        "geotex_version": VERSION,
        "recipe": shell.recipe,
    }


def save_shell(path, shell: Shell) -> Path:
    """Write ``shell`` to ``path`` (``.npz``), atomically and reproducibly.

    Raises
    ------
    InputError
        If the path does not end in ``.npz``.
    MeshFileError
        If the file cannot be written.
    """
    arrays = {key: np.ascontiguousarray(np.asarray(arr).astype(_ARRAYS[key]))
              for key, arr in _arrays_of(shell).items()}
    meta = json.dumps(shell_metadata(shell), sort_keys=True)
    arrays["metadata"] = np.frombuffer(meta.encode("utf-8"), dtype=np.uint8)
    return write_record(path, arrays, compressed=True, date_time=_DATE, kind="shell")


def load_shell(path) -> Shell:
    """Read a shell file written by :func:`save_shell`.

    Raises
    ------
    MissingFileError
        If the file does not exist.
    MeshFileError
        If it is not a geotex shell file, or is truncated or corrupted.
    """
    path = Path(path)
    arrays, meta = read_record(path, kind="shell", format=FORMAT, arrays=list(_ARRAYS),
                               hint=_HINT)
    try:
        return _shell_of(arrays, meta, path)
    except (KeyError, TypeError, ValueError, IndexError, GeotexError):
        raise MeshFileError(path, "inconsistent shell file (array shapes, indices or metadata "
                            "do not match); " + _HINT) from None


def shell_file_metadata(path) -> dict:
    """The JSON metadata of a shell file, without reading its arrays.

    Raises
    ------
    MissingFileError, MeshFileError
        As :func:`load_shell`.
    """
    return read_record(path, kind="shell", format=FORMAT, arrays=(), hint=_HINT)[1]


def _shell_of(a: dict, meta: dict, path) -> Shell:
    corners = a["quad_corners"].astype(np.int64)
    labels = a["quad_label"].astype(np.int64)
    q = labels.size
    res = int(meta["res"])
    if (corners.shape != (q, 4, 3) or q == 0 or labels.min() < 0 or labels.max() > 5
            or not 1 <= res <= 16 or a["origin"].shape != (3,)):
        raise InputError("quads")
    P, F, grid = subdivided_quads(corners, labels, res=res)
    n = P.shape[0]
    bv, bf = a["base_vertices"], a["base_faces"].astype(np.int64)
    if (a["Y"].shape != (n, 3) or a["D"].shape != (n, 3) or a["quad_folded"].shape != (q,)
            or bv.ndim != 2 or bv.shape[1] != 3 or bf.ndim != 2 or bf.shape[1] != 3
            or bf.shape[0] == 0 or bf.min() < 0 or bf.max() >= bv.shape[0]):
        raise InputError("arrays")
    diagnostics = PolyCubeDiagnostics(**{k: dict(meta.get(k, {})) for k in (
        "distortion", "coverage", "voxels", "tile_search")})
    pc = PolyCube(tile_size=float(meta["tile_size"]), res=res,
                  origin=a["origin"].astype(np.float64), P=P, Y=a["Y"].astype(np.float64),
                  F=F, quad_folded=a["quad_folded"].astype(bool),
                  layout=QuadLayout.of_quads(corners, labels, grid), diagnostics=diagnostics)
    return Shell(name=str(meta.get("name", Path(path).stem)), polycube=pc,
                 D=a["D"].astype(np.float64), max_height=float(meta["max_height"]),
                 base_vertices=bv.astype(np.float64), base_faces=bf,
                 source=str(meta.get("source", "")), recipe=dict(meta.get("recipe", {})))
