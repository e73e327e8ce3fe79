"""Height-and-tilt geometric texture (Andersen, Desbrun, Bærentzen, Aanæs).

A textured mesh ``V0`` over a base ``Vs`` with the same connectivity is
stored as a pseudo-height per vertex and a tilt 1-form per edge (the
paper's bounded least squares, plus a per-vertex residual that makes the
round trip exact):

>>> from geotex.heighttilt import spiky_sphere, extract_texture, apply_texture
>>> V0, F, Vs = spiky_sphere(subdivisions=2, spikes=6, seed=0)
>>> tex, Vs = extract_texture(V0, F, base=Vs)
>>> bool(abs(apply_texture(Vs, F, tex) - V0).max() < 1e-9)
True
"""

from geotex.heighttilt.base import (base_normals, decode_tilt, encode_tilt, smoothed_base,
                                    tilt_frames)
from geotex.heighttilt.deform import (bend, deformed_texture, naive_space_deformation,
                                      reapplied, scale_base, twist)
from geotex.heighttilt.edit import scale_height, set_tilt, wiggle, wrap
from geotex.heighttilt.extract import displacement_to_height_tilt, extract_texture
from geotex.heighttilt.planar import PlanarTransfer, transfer_planar
from geotex.heighttilt.procedural import bumpy_plane, spiky_sphere, tentacle_stick
from geotex.heighttilt.refine import refine_base
from geotex.heighttilt.reconstruct import apply_texture, displacements
from geotex.heighttilt.texture import HeightTiltTexture, load_texture, save_texture
from geotex.heighttilt.transfer import (ShapeTransferReport, closest_point_correspondence,
                                        sphere_correspondence, transfer_between_shapes,
                                        transfer_texture)

__all__ = [
    "HeightTiltTexture", "save_texture", "load_texture",
    "smoothed_base", "base_normals", "tilt_frames", "encode_tilt", "decode_tilt",
    "extract_texture", "displacement_to_height_tilt",
    "apply_texture", "displacements",
    "set_tilt", "scale_height", "wrap", "wiggle",
    "spiky_sphere", "bumpy_plane", "tentacle_stick",
    "reapplied", "deformed_texture", "bend", "twist", "scale_base", "naive_space_deformation",
    "transfer_texture", "closest_point_correspondence",
    "transfer_between_shapes", "sphere_correspondence", "ShapeTransferReport",
    "transfer_planar", "PlanarTransfer", "refine_base",
]
