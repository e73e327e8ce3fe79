"""geotex: geometric texture on triangle meshes, made printable."""

from geotex.errors import (GeotexError, InputError, MeshFileError, MissingFileError,
                           NotPrintableError, UnsupportedFormatError)
from geotex.mesh import Mesh
from geotex.version import VERSION as __version__

__all__ = [
    "Mesh",
    "GeotexError", "InputError", "MeshFileError", "MissingFileError",
    "NotPrintableError", "UnsupportedFormatError",
]
