"""Height-field relief on a refined base: the displacement core.

:func:`displaced_solid` displaces a base by any height sampler (a mapped
image, a lapped texture, a pattern); :func:`relief_points` gives the refined
surface points and normals such a sampler works on;
:func:`refined_by_edge_splits` is the shape-exact adaptive refinement.
"""

from geotex.relief.core import (DEFAULT_MAX_FACES, RELIEF_ROUNDS, RELIEF_STAGES, ReliefPoints,
                                ReliefResult, displaced_solid, edge_length_for_faces,
                                relief_points)
from geotex.relief.subdivide import RefinedMesh, refined_by_edge_splits

__all__ = ["displaced_solid", "relief_points", "ReliefPoints", "ReliefResult",
           "edge_length_for_faces", "refined_by_edge_splits", "RefinedMesh",
           "RELIEF_STAGES", "RELIEF_ROUNDS", "DEFAULT_MAX_FACES"]
