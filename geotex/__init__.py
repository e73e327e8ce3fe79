"""geotex: geometric texture on triangle meshes, made printable."""

from geotex.errors import (GeotexError, InputError, MeshFileError, MissingFileError,
                           NotPrintableError, UnsupportedFormatError)
from geotex.mesh import Mesh

__version__ = "0.1.0"

__all__ = [
    "Mesh",
    "GeotexError", "InputError", "MeshFileError", "MissingFileError",
    "NotPrintableError", "UnsupportedFormatError",
]
