"""Shared fixtures: small generated meshes and the committed broken corpus."""

from __future__ import annotations

import fcntl
import os
from pathlib import Path

import numpy as np
import pytest

from geotex.mesh.primitives import box, icosphere, torus

DATA = Path(__file__).parent / "data"
BROKEN = DATA / "broken"


@pytest.fixture(scope="session")
def shared_tileset(tmp_path_factory):
    """``get(key, build)``: the tile set ``build()`` makes, built once per test run.

    Several test files use the same tile sets (tens of seconds each to build).
    The first xdist worker to ask builds the set and saves it
    (:func:`geotex.tiles.tileset.save_tileset`, exact: tile sets hold float32
    values) in the run's temporary folder, which the workers share; the others
    wait for it on a lock and load it.  ``key`` names the set and must differ
    whenever ``build`` does.
    """
    from geotex.tiles.tileset import load_tileset, save_tileset

    root = tmp_path_factory.getbasetemp()
    if os.environ.get("PYTEST_XDIST_WORKER"):
        root = root.parent                   # pytest-N/popen-gwK: pytest-N is this run's
    folder = root / "shared-tilesets"
    folder.mkdir(exist_ok=True)

    def get(key, build):
        path = folder / f"{key}.npz"
        with open(folder / f"{key}.lock", "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if not path.exists():
                save_tileset(path, build())
        return load_tileset(path)

    return get


@pytest.fixture(scope="module")
def studs(shared_tileset):
    """A complete one-colour studs set (6 tiles), built once per test run."""
    from geotex.exemplars import exemplar
    from geotex.tiles import build_tileset

    return shared_tileset("studs-res6-1-seed0-paste", lambda: build_tileset(
        exemplar("studs", seed=1, resolution=6), colors=1, seed=0, interior="paste"))


@pytest.fixture(scope="module")
def torus_shell():
    """Shell of a thin-ish torus on a coarse grid (tile 0.4): its voxel staircases
    make the quads rectangles and rhombi (mean conformal ratio well above 1)."""
    from geotex.shells import build_shell

    V, F = torus(1.0, 0.4, n_major=48, n_minor=24)
    return build_shell(V, F, tile_size=0.4, name="torus")


@pytest.fixture
def tet():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]], dtype=np.int64)
    return V, F


@pytest.fixture
def sphere():
    return icosphere(3)


@pytest.fixture
def ring():
    return torus(1.0, 0.35, n_major=32, n_minor=16)


@pytest.fixture
def cube():
    return box(divisions=2)
