"""Sample meshes and images shipped with geotex (see NOTICE.md for origin and licence).

The examples and benchmarks prefer the larger test data of a development
checkout (``shared/data`` beside the repository, :func:`shared_data_dir`) and
fall back to these samples, so that they run the same way in a clean clone
or an installed package.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path

from geotex.errors import InputError

__all__ = ["sample_path", "shared_data_dir", "SAMPLES", "SAMPLE_IMAGES"]

#: Sample mesh name -> file name inside this package.
SAMPLES = {"spot": "spot_lowres.obj", "bob": "bob.ply", "blub": "blub_lowres.obj",
           "teapot-open": "teapot_open.stl"}

#: Sample image name -> file name inside this package (256 x 256 copies, NOTICE.md):
#: two colour photos (a brick wall, sunlit water) and two grey depth maps
#: (knitted wool, a brick wall; light is deep, as in Godot 3: invert for a height).
SAMPLE_IMAGES = {"bricks": "embark_bricks.jpg", "water": "embark_water.jpg",
                 "wool-height": "godot_wool_depth.png",
                 "bricks-height": "godot_bricks_depth.png"}

#: Environment variable that names the test data folder (overrides the search).
SHARED_DATA_ENV = "GEOTEX_SHARED_DATA"


def sample_path(name: str) -> Path:
    """Return the path of a bundled sample mesh or image.

    Parameters
    ----------
    name : str
        One of ``SAMPLES`` (meshes) or ``SAMPLE_IMAGES`` (images).

    Returns
    -------
    pathlib.Path
        The file inside the installed package.

    Raises
    ------
    InputError
        For an unknown name.
    """
    file = SAMPLES.get(name) or SAMPLE_IMAGES.get(name)
    if file is None:
        raise InputError(f"unknown sample {name!r}; choose one of "
                         f"{', '.join([*SAMPLES, *SAMPLE_IMAGES])}")
    return Path(str(resources.files("geotex.data").joinpath(file)))


def shared_data_dir(start: str | os.PathLike, *, levels: int = 3) -> Path | None:
    """Return the test data folder beside a development checkout, or None.

    The larger test meshes and images (``shared/data``, not part of the
    repository; its ``MANIFEST.md`` gives every file's origin and licence)
    sit beside the repository: ``REPO/../shared/data``, or one folder higher
    for a git worktree.  A clean clone or an installed package has none, and
    the examples then use the bundled samples (:func:`sample_path`).

    Parameters
    ----------
    start : str or os.PathLike
        A file or folder inside the checkout (an example passes
        ``sys.argv[0]``).
    levels : int, optional
        How many folders above ``start``'s folder are searched.

    Returns
    -------
    pathlib.Path or None
        ``$GEOTEX_SHARED_DATA`` when set (None if it is not a folder), else
        the first ``shared/data`` folder in ``start``'s folder or the
        ``levels`` folders above it, else None.
    """
    env = os.environ.get(SHARED_DATA_ENV)
    if env:
        return Path(env) if Path(env).is_dir() else None
    here = Path(start).resolve()
    folder = here if here.is_dir() else here.parent
    for p in [folder, *folder.parents][:levels + 1]:
        if (p / "shared" / "data").is_dir():
            return p / "shared" / "data"
    return None
