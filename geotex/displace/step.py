"""STEP/STP parts tessellated by gmsh's OpenCASCADE kernel.

gmsh (PyPI ``gmsh``, an optional dependency) imports the B-rep, meshes every
face with a size limit from a preset (a fraction of the part's diagonal)
and curvature refinement (``Mesh.MeshSizeFromCurvature``: elements per full
turn), sharing the nodes of the curves between faces, so a closed solid
gives a closed, welded triangle mesh.  Triangles are then oriented
consistently and outward (:func:`geotex.repair.orient.outward_oriented`).
Coordinates are read as millimetres (OpenCASCADE's unit for STEP).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from geotex.errors import InputError
from geotex.mesh.topology import compacted
from geotex.repair.orient import consistently_oriented, outward_oriented

__all__ = ["read_step", "STEP_PRESETS"]

#: Largest element as a fraction of the part's diagonal, and elements per full turn.
STEP_PRESETS = {"coarse": (0.05, 16), "standard": (0.02, 32), "fine": (0.008, 64)}


def read_step(path, *, quality: str = "standard") -> tuple[np.ndarray, np.ndarray]:
    """Tessellate a STEP file into a closed triangle mesh.

    Parameters
    ----------
    path : str or os.PathLike
        ``.step`` / ``.stp`` file.
    quality : {"coarse", "standard", "fine"}, optional

    Returns
    -------
    V : numpy.ndarray, (n, 3) float64
    F : numpy.ndarray, (m, 3) int64

    Raises
    ------
    InputError
        gmsh not installed, a missing or unreadable file, no surface, or an
        unknown preset.
    """
    p = Path(path)
    if quality not in STEP_PRESETS:
        raise InputError(f"quality must be one of {', '.join(STEP_PRESETS)}, got {quality!r}")
    if not p.is_file():
        raise InputError(f"{p}: no such file")
    try:
        import gmsh
    except ImportError:
        raise InputError(f"{p}: reading STEP needs gmsh (pip install gmsh); or export the part "
                         "as STL/3MF from your CAD program") from None
    frac, per_turn = STEP_PRESETS[quality]
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("General.Verbosity", 0)
        try:
            gmsh.model.occ.importShapes(str(p))
            gmsh.model.occ.synchronize()
        except Exception as exc:  # gmsh raises plain Exception with its log line
            raise InputError(f"{p}: not a readable STEP file ({exc})") from None
        ents = gmsh.model.getEntities(3) or gmsh.model.getEntities(2)
        if not ents:
            raise InputError(f"{p}: the STEP file holds no surface")
        box = np.array(gmsh.model.getBoundingBox(-1, -1), dtype=np.float64)
        diag = float(np.linalg.norm(box[3:] - box[:3]))
        gmsh.option.setNumber("Mesh.MeshSizeMax", frac * diag)
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.0)
        gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", per_turn)
        gmsh.option.setNumber("Mesh.Algorithm", 6)
        gmsh.model.mesh.generate(2)
        tags, coords, _ = gmsh.model.mesh.getNodes()
        types, _, nodes = gmsh.model.mesh.getElements(2)
    finally:
        gmsh.finalize()
    tri = [np.asarray(n, dtype=np.int64).reshape(-1, 3) for t, n in zip(types, nodes) if t == 2]
    if not tri:
        raise InputError(f"{p}: gmsh produced no triangles")
    tags = np.asarray(tags, dtype=np.int64)
    V = np.asarray(coords, dtype=np.float64).reshape(-1, 3)
    index = np.full(int(tags.max()) + 1, -1, dtype=np.int64)
    index[tags] = np.arange(tags.size)
    F = index[np.concatenate(tri)]

    V, F = compacted(V, F)
    F, _ = consistently_oriented(F)
    F, _ = outward_oriented(V, F)
    return np.ascontiguousarray(V), np.ascontiguousarray(F, dtype=np.int64)
