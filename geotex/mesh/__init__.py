"""Core mesh arrays: the record type, validation, topology and geometry."""

from geotex.mesh.arrays import as_faces, as_mesh_arrays, as_vertices
from geotex.mesh.geometry import (bounding_box, component_volumes, degenerate_faces,
                                  face_areas, face_normals, signed_volume)
from geotex.mesh.record import Mesh
from geotex.mesh.topology import (EdgeTopology, duplicate_face_groups, edge_topology,
                                  face_components, half_edges, non_manifold_vertices,
                                  vertex_components)

__all__ = [
    "Mesh", "as_vertices", "as_faces", "as_mesh_arrays",
    "EdgeTopology", "edge_topology", "half_edges", "vertex_components",
    "face_components", "non_manifold_vertices", "duplicate_face_groups",
    "face_areas", "face_normals", "signed_volume", "component_volumes",
    "bounding_box", "degenerate_faces",
]
