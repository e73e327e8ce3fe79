"""The README's and the documentation pages' local links point to committed files.

Generated pictures are not committed (``docs/gallery/*.png`` is ignored; the
documentation build runs the examples); the few that README.md and the pages
show directly are, and must stay so.
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")),
         *sorted((ROOT / "docs").glob("*.rst")), ROOT / "viewer" / "README.md"]
#: Markdown links and images ``](target)``, reStructuredText ``image::``/``figure::``
LINK = re.compile(r"\]\(([^)\s]+)\)|\.\. (?:image|figure):: (\S+)")
#: pages of the built site, not files in the repository
BUILT = ("generated/", "auto_examples/", "api/")


def _targets(page: Path):
    for m in LINK.finditer(page.read_text(encoding="utf-8")):
        target = (m.group(1) or m.group(2)).split("#")[0]
        if not target or re.match(r"[a-z]+:", target) or target.startswith(BUILT):
            continue
        yield target


def _tracked() -> set[str] | None:
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        return None
    p = subprocess.run(["git", "-C", str(ROOT), "ls-files"], capture_output=True, text=True)
    return set(p.stdout.splitlines()) if p.returncode == 0 else None


@pytest.mark.parametrize("page", PAGES, ids=[str(p.relative_to(ROOT)) for p in PAGES])
def test_local_links_point_to_committed_files(page):
    tracked = _tracked()
    missing = []
    for target in _targets(page):
        path = (page.parent / target).resolve()
        rel = path.relative_to(ROOT).as_posix() if path.is_relative_to(ROOT) else None
        if not path.exists():
            missing.append(target)
        elif tracked is not None and path.is_file() and rel not in tracked:
            missing.append(f"{target} (not committed)")
    assert missing == []


def test_the_site_shows_the_pictures_of_its_own_build(tmp_path):
    import sys
    sys.path.insert(0, str(ROOT / "docs"))
    try:
        import geotex_sphinx
    finally:
        sys.path.remove(str(ROOT / "docs"))
    out = tmp_path / "_build" / "gallery-out"
    for stem, name in (("pgp_relief", "pgp_relief.png"), ("tiles", "tiles_knurl_tiling.png"),
                       ("tiles", "notes.txt")):
        (out / stem).mkdir(parents=True, exist_ok=True)
        (out / stem / name).write_bytes(b"")
    pictures = geotex_sphinx.built_pictures(out)
    assert sorted(pictures) == ["pgp_relief.png", "tiles_knurl_tiling.png"]
    text = ("![pgp relief](gallery/pgp_relief.png)\n![q](gallery/quilting.png)\n"
            ".. image:: gallery/tiles_knurl_tiling.png\n")
    new = geotex_sphinx.use_built_pictures(text, "guide", pictures, tmp_path)
    assert new.splitlines() == [
        "![pgp relief](_build/gallery-out/pgp_relief/pgp_relief.png)",
        "![q](gallery/quilting.png)",                 # not made in this build: committed
        ".. image:: _build/gallery-out/tiles/tiles_knurl_tiling.png"]
    deeper = geotex_sphinx.use_built_pictures(text, "api/geotex", pictures, tmp_path)
    assert "](../_build/gallery-out/pgp_relief/pgp_relief.png)" in deeper
