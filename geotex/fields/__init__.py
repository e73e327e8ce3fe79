"""Fields over surfaces: tangent directions, scalar fields, discrete 1-forms.

=================  ==========================================================
``frames``         per-face tangent frames and the discrete connection
``directions``     projected, principal-curvature and smooth N-direction fields
``singularities``  vertex indices of per-face N-direction fields
``combing``        consistent representatives for N > 1, with cut edges
``rbf``            RBF interpolation of directions over surface distance
``oneforms``       1-forms: encode, Whitney decode, evaluate, line integrals
``scalar``         Laplacian interpolation of scale and material fields
``store``          direction field files (.npz)
=================  ==========================================================
"""

from geotex.fields.combing import CombedField, comb_direction_field, combed_vectors
from geotex.fields.directions import (Constraint, DirectionField, PrincipalDirections,
                                      constraint_scale_field, principal_direction_field,
                                      projected_direction_field, smooth_direction_field)
from geotex.fields.frames import (FaceConnection, face_connection, face_frames,
                                  tangent_angles, vectors_from_angles, wrap_angle)
from geotex.fields.oneforms import (circulation, decode_one_form, decode_one_form_at_vertices,
                                    encode_one_form, evaluate_one_form, exterior_derivative,
                                    integrate_edges, line_integrals, segment_samples,
                                    whitney_corner_vectors)
from geotex.fields.rbf import KERNELS, rbf_direction_field, surface_distances
from geotex.fields.scalar import interpolate_scalar, material_field, scale_field, vertex_to_face
from geotex.fields.singularities import angle_defects, index_sum, singularities, vertex_indices
from geotex.fields.store import (FIELD_FORMAT, FieldFile, load_direction_field,
                                 save_direction_field)

__all__ = [
    "face_frames", "FaceConnection", "face_connection", "tangent_angles",
    "vectors_from_angles", "wrap_angle",
    "Constraint", "DirectionField", "PrincipalDirections", "projected_direction_field",
    "principal_direction_field", "smooth_direction_field", "constraint_scale_field",
    "singularities", "index_sum", "vertex_indices", "angle_defects",
    "CombedField", "comb_direction_field", "combed_vectors",
    "rbf_direction_field", "KERNELS", "surface_distances",
    "encode_one_form", "decode_one_form", "decode_one_form_at_vertices", "evaluate_one_form",
    "whitney_corner_vectors", "exterior_derivative", "circulation", "segment_samples",
    "line_integrals", "integrate_edges",
    "interpolate_scalar", "scale_field", "material_field", "vertex_to_face",
    "save_direction_field", "load_direction_field", "FieldFile", "FIELD_FORMAT",
]
