"""Every example script runs and writes its picture."""

import os
import subprocess
import sys
from pathlib import Path

import pytest
from PIL import Image

EXAMPLES = sorted((Path(__file__).parents[1] / "examples").glob("*.py"))


@pytest.mark.slow
@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_writes_pictures(script, tmp_path):
    env = dict(os.environ, GEOTEX_EXAMPLES_QUICK="1")   # heavy examples draw less
    p = subprocess.run([sys.executable, str(script), str(tmp_path)], capture_output=True,
                       text=True, timeout=600, env=env)
    assert p.returncode == 0, p.stderr[-2000:]
    pictures = [f for f in tmp_path.rglob("*.png") if f.stem == script.stem or
                f.name.startswith(script.stem)]
    assert pictures, f"{script.name} wrote no picture named after it"
    for f in pictures:
        with Image.open(f) as im:
            assert im.size[0] >= 200 and im.size[1] >= 150


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_runs_without_file_variable(script):
    """sphinx-gallery runs an example without ``__file__``: only the ``__main__``
    block's default output folder may use it (docs/gallery-examples.md)."""
    import ast

    tree = ast.parse(script.read_text(encoding="utf-8"))
    allowed = set()
    for node in tree.body:
        if (isinstance(node, ast.If) and isinstance(node.test, ast.Compare)
                and getattr(node.test.left, "id", None) == "__name__"):
            allowed.update(id(n) for n in ast.walk(node))
    uses = [n.lineno for n in ast.walk(tree)
            if isinstance(n, ast.Name) and n.id == "__file__" and id(n) not in allowed]
    assert uses == [], f"__file__ at lines {uses}: use Path(sys.argv[0])"


@pytest.mark.parametrize("script", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_docstring_starts_with_a_title(script):
    """The gallery's caption: a reStructuredText title (docs/gallery-examples.md)."""
    import ast

    doc = ast.get_docstring(ast.parse(script.read_text(encoding="utf-8")), clean=False)
    lines = (doc or "").strip("\n").splitlines()
    assert len(lines) >= 2 and lines[0].strip(), "the docstring starts with a title line"
    assert set(lines[1]) == {"="} and len(lines[1]) >= len(lines[0]), \
        "the title is underlined with = at least as long as it"
