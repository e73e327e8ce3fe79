"""Procedural exemplar geometric textures: planar patches of separate closed elements.

>>> from geotex.exemplars import exemplar, EXEMPLAR_KINDS
>>> ex = exemplar("studs", size=(4, 4), seed=0)
>>> ex.vertices.shape, ex.faces.shape, int(ex.elements().max() + 1)
((3200, 3), (6144, 3), 64)

Kinds: ``studs``, ``scales``, ``knurl``, ``weave``, ``chainmail``, ``bark``.
Every element is closed, edge-manifold, outward oriented and free of
self-intersections; elements never touch each other, lie over
``[0, lx] x [0, ly]`` and reach down to ``z = -depth`` so that a union with a
base below ``z = 0`` fuses them.
"""

from geotex.exemplars.record import Exemplar
from geotex.exemplars.registry import EXEMPLAR_KINDS, describe, exemplar, kind_parameters
from geotex.exemplars.store import load_exemplar, save_exemplar

__all__ = ["Exemplar", "exemplar", "EXEMPLAR_KINDS", "describe", "kind_parameters",
           "save_exemplar", "load_exemplar"]
