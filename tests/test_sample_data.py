"""The bundled samples (geotex/data) and the lookup of the test data beside a checkout."""

from __future__ import annotations

from pathlib import Path

import pytest
from PIL import Image

from geotex.data import SAMPLE_IMAGES, SAMPLES, sample_path, shared_data_dir
from geotex.errors import InputError

NOTICE = (Path(__file__).resolve().parents[1] / "geotex" / "data" / "NOTICE.md").read_text(
    encoding="utf-8")


@pytest.mark.parametrize("name", [*SAMPLES, *SAMPLE_IMAGES])
def test_every_sample_is_there_and_has_a_notice_row(name):
    path = sample_path(name)
    assert path.is_file()
    assert f"| `{path.name}` |" in NOTICE, f"{path.name} has no row in NOTICE.md"


@pytest.mark.parametrize("name", SAMPLE_IMAGES)
def test_sample_images_are_small_real_pictures(name):
    with Image.open(sample_path(name)) as im:
        im.load()
        assert im.size == (256, 256)
        assert im.mode in ("L", "RGB")
        lo, hi = im.convert("L").getextrema()
    assert hi - lo > 100, "a picture, not a flat image"


def test_sample_images_stay_small():
    total = sum(sample_path(n).stat().st_size for n in SAMPLE_IMAGES)
    assert total < 300_000


def test_unknown_sample_is_an_input_error():
    with pytest.raises(InputError, match="bricks"):
        sample_path("no-such-sample")


def test_shared_data_dir_is_found_beside_a_checkout_or_a_worktree(tmp_path, monkeypatch):
    monkeypatch.delenv("GEOTEX_SHARED_DATA", raising=False)
    (tmp_path / "shared" / "data").mkdir(parents=True)
    script = tmp_path / "repo" / "examples" / "x.py"            # a checkout beside shared/
    script.parent.mkdir(parents=True)
    script.touch()
    assert shared_data_dir(script) == tmp_path / "shared" / "data"
    deeper = tmp_path / "wt" / "name" / "examples" / "x.py"     # a worktree one folder deeper
    deeper.parent.mkdir(parents=True)
    deeper.touch()
    assert shared_data_dir(deeper) == tmp_path / "shared" / "data"
    assert shared_data_dir(deeper, levels=2) is None


def test_shared_data_dir_is_none_in_a_clean_clone(tmp_path, monkeypatch):
    monkeypatch.delenv("GEOTEX_SHARED_DATA", raising=False)
    script = tmp_path / "clone" / "examples" / "x.py"
    script.parent.mkdir(parents=True)
    script.touch()
    assert shared_data_dir(script) is None


def test_shared_data_dir_follows_the_environment(tmp_path, monkeypatch):
    monkeypatch.setenv("GEOTEX_SHARED_DATA", str(tmp_path))
    assert shared_data_dir("/anywhere/x.py") == tmp_path
    monkeypatch.setenv("GEOTEX_SHARED_DATA", str(tmp_path / "missing"))
    assert shared_data_dir("/anywhere/x.py") is None
