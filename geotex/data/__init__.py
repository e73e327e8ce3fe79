"""Sample meshes shipped with geotex (see NOTICE.md for origin and licence)."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from geotex.errors import InputError

__all__ = ["sample_path", "SAMPLES"]

#: Sample name -> file name inside this package.
SAMPLES = {"spot": "spot_lowres.obj", "bob": "bob.ply", "blub": "blub_lowres.obj",
           "teapot-open": "teapot_open.stl"}


def sample_path(name: str) -> Path:
    """Return the path of a bundled sample mesh.

    Parameters
    ----------
    name : str
        One of ``SAMPLES``.

    Raises
    ------
    InputError
        For an unknown name.
    """
    if name not in SAMPLES:
        raise InputError(f"unknown sample {name!r}; choose one of {', '.join(SAMPLES)}")
    return Path(str(resources.files("geotex.data").joinpath(SAMPLES[name])))
