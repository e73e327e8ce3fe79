"""Fields over surfaces: tangent directions, scalar fields, discrete 1-forms."""
