"""The installed distribution carries the catalogs and sample data (package data).

The test suite imports the source tree (``pythonpath = ["."]`` in pyproject.toml,
so tests and doctests see one geotex); this test reads the *installed*
distribution's file list instead, so a packaging mistake (a catalog left out of
the wheel) still fails under CI, where ``pip install ".[test]"`` is not editable.
"""

from __future__ import annotations

import json
import os
import sysconfig
from importlib import metadata
from pathlib import Path

import pytest

SOURCE = Path(__file__).resolve().parents[1] / "geotex"


def _installed_files():
    # the distribution installed in site-packages (not an egg-info in the source tree)
    site = sysconfig.get_paths()["purelib"]
    found = list(metadata.distributions(name="geotex", path=[site]))
    if not found:
        if os.environ.get("CI"):
            pytest.fail(f"geotex is not installed in {site}")
        pytest.skip("geotex is not installed")
    dist = found[0]
    direct = dist.read_text("direct_url.json")
    if direct and json.loads(direct).get("dir_info", {}).get("editable"):
        if os.environ.get("CI"):
            pytest.fail("CI installs geotex non-editable (pip install '.[test]')")
        pytest.skip("editable install: the package data is the source tree itself")
    return {str(f).replace("\\", "/") for f in dist.files or ()}


@pytest.mark.parametrize("folder, pattern", [
    ("tiles/catalog", "*.npz"), ("tiles/catalog", "recipes.json"),
    ("shells/catalog", "*.npz"), ("shells/catalog", "recipes.json"),
    ("data", "*.obj"), ("data", "*.ply"), ("data", "*.jpg"), ("data", "*.png"),
    ("data", "NOTICE.md"),
])
def test_wheel_carries_the_package_data(folder, pattern):
    files = _installed_files()
    wanted = sorted((SOURCE / folder).glob(pattern))
    assert wanted, f"nothing matches geotex/{folder}/{pattern} in the source tree"
    for path in wanted:
        assert f"geotex/{folder}/{path.name}" in files, f"{path.name} missing from the wheel"
