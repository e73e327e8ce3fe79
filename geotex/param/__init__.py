"""Parameterizations: local (field-aligned, harmonic, LSCM) with distortion measures."""

from geotex.param.distortion import (DistortionStat, DistortionSummary, FaceDistortion,
                                     distortion_summary, face_distortion, face_jacobians,
                                     singular_values)
from geotex.param.local import (field_aligned_parameterization, gradient_operator,
                                harmonic_parameterization, lscm_parameterization)

__all__ = [
    "field_aligned_parameterization", "harmonic_parameterization", "lscm_parameterization",
    "gradient_operator",
    "face_jacobians", "singular_values", "FaceDistortion", "face_distortion",
    "DistortionStat", "DistortionSummary", "distortion_summary",
]
