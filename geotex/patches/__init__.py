"""Surface patches: disc-region growing, face-cluster hierarchies, effect areas."""

from geotex.patches.clusters import (ClusterHierarchy, ClusterLevel, cluster_hierarchy,
                                     disc_clusters, is_disc_partition)
from geotex.patches.effect import effect_area
from geotex.patches.grow import (FaceAdjacency, Patch, boundary_loops, face_adjacency,
                                 grow_patch, is_disc)

__all__ = [
    "FaceAdjacency", "face_adjacency", "Patch", "grow_patch", "is_disc", "boundary_loops",
    "ClusterLevel", "ClusterHierarchy", "cluster_hierarchy", "is_disc_partition",
    "disc_clusters", "effect_area",
]
