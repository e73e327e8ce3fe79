"""Shared fixtures: small generated meshes and the committed broken corpus."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from geotex.mesh.primitives import box, icosphere, torus

DATA = Path(__file__).parent / "data"
BROKEN = DATA / "broken"


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
