"""Sphinx helpers of the geotex documentation (loaded by conf.py as an extension).

* ``builder-inited``: writes the generated pages - the CLI reference walked
  from :func:`geotex.cli.build_parser`, and one page per benchmark result in
  ``benchmarks/results/*.md`` (included with myst).
* ``source-read``: links from ``docs/*.md`` to ``../benchmarks/results/X.md``
  (right on GitHub) point to the generated pages in the site, and the
  committed pictures ``gallery/NAME.png`` a page shows are replaced by the
  ones the examples wrote in this build (:func:`use_built_pictures`).
* :func:`output_scraper`: a sphinx-gallery image scraper that picks up the
  PNG pictures an example wrote into its output folder, and embeds every GLB
  it wrote in the interactive 3D viewer (``geotex.viewpage``).
"""

from __future__ import annotations

import argparse
import re
import shutil
import textwrap
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
GENERATED = DOCS / "generated"
GALLERY_OUT = DOCS / "_build" / "gallery-out"
#: GLBs larger than this are linked for download instead of embedded in the page.
MAX_EMBEDDED_GLB = 24 * 1024 * 1024


def _write_if_changed(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


def _title(text: str, char: str) -> str:
    return f"{text}\n{char * len(text)}\n"


def cli_reference() -> str:
    """Return the reStructuredText of the CLI reference, from the argparse parsers."""
    from geotex.cli import build_parser

    parser = build_parser()
    out = [".. _cli-reference:\n", _title("Command line reference", "="),
           "Generated from the argument parsers of :mod:`geotex.cli` (the same text as "
           "``geotex COMMAND --help``).\n",
           ".. code-block:: text\n", textwrap.indent(parser.format_help(), "   ")]
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    helps = {a.dest: a.help for a in sub._choices_actions}
    for name, p in sub.choices.items():
        out.append(_title(f"geotex {name}", "-"))
        if helps.get(name):
            out.append(helps[name].rstrip(".") + ".\n")
        out.append(".. code-block:: text\n")
        out.append(textwrap.indent(p.format_help(), "   "))
    return "\n".join(out)


def benchmark_pages() -> list[str]:
    """Write one page per ``benchmarks/results/*.md`` and return their names."""
    names = []
    for md in sorted((ROOT / "benchmarks" / "results").glob("*.md")):
        names.append(md.stem)
        _write_if_changed(GENERATED / "benchmarks" / f"{md.stem}.md",
                          f"```{{include}} ../../../benchmarks/results/{md.name}\n```\n")
    index = ["# Benchmark results\n",
             "Each page is a table written by a script in `benchmarks/` (see the "
             "[benchmarks overview](../../benchmarks.md)).\n",
             "```{toctree}\n:maxdepth: 1\n", *names, "```\n"]
    _write_if_changed(GENERATED / "benchmarks" / "index.md", "\n".join(index))
    return names


def _generate(app) -> None:
    _write_if_changed(GENERATED / "cli.rst", cli_reference())
    benchmark_pages()


_RESULT_LINK = re.compile(r"\]\(\.\./benchmarks/results/([\w.-]+)\.md\)")


#: a committed picture shown by a page: Markdown ``](gallery/NAME.png)`` or
#: reStructuredText ``image::``/``figure:: gallery/NAME.png``
_PICTURE = re.compile(r"(\]\(|\.\. (?:image|figure):: )gallery/([\w.-]+\.png)")


def built_pictures(out: Path = GALLERY_OUT) -> dict[str, Path]:
    """Return the pictures the gallery examples wrote in this build, by file name.

    Parameters
    ----------
    out : pathlib.Path, optional
        The examples' output folders (one per example).

    Returns
    -------
    dict of str to pathlib.Path
        ``NAME.png`` -> the file an example wrote (the first in sorted
        order when two wrote the same name).
    """
    found: dict[str, Path] = {}
    for png in sorted(out.glob("*/*.png")):
        found.setdefault(png.name, png)
    return found


def use_built_pictures(text: str, docname: str, pictures: dict[str, Path],
                       srcdir: Path = DOCS) -> str:
    """Point a page's ``gallery/NAME.png`` pictures to the ones this build made.

    ``docs/gallery`` keeps the few pictures that the README and the pages
    show (readable on GitHub too); in the site a page shows the picture its
    example wrote in this build, so that it is never older than the code.
    A picture no example wrote in this build (a partial build) stays the
    committed one.

    Parameters
    ----------
    text : str
        The page's source.
    docname : str
        The page's name (``guide``, ``api/geotex.render``): links are
        relative to its folder.
    pictures : dict of str to pathlib.Path
        :func:`built_pictures`.
    srcdir : pathlib.Path, optional
        The documentation's source folder.

    Returns
    -------
    str
        The source with the links replaced.
    """
    up = "../" * docname.count("/")

    def replace(m):
        built = pictures.get(m.group(2))
        if built is None or not built.is_relative_to(srcdir):
            return m.group(0)
        return m.group(1) + up + built.relative_to(srcdir).as_posix()

    return _PICTURE.sub(replace, text)


def _rewrite_links(app, docname, source) -> None:
    if docname == "benchmarks":
        source[0] = _RESULT_LINK.sub(r"](generated/benchmarks/\1.md)", source[0])
    if "gallery/" in source[0]:
        source[0] = use_built_pictures(source[0], docname, built_pictures(),
                                       Path(app.srcdir))


def public_modules() -> list[str]:
    """Return the names of geotex's public modules (no ``_`` part), the CLI left out."""
    import pkgutil

    import geotex

    names = []
    for info in pkgutil.walk_packages(geotex.__path__, "geotex."):
        parts = info.name.split(".")
        if any(p.startswith("_") for p in parts) or parts[1] in ("cli",):
            continue
        names.append(info.name)
    return sorted(["geotex", *names])


def _first_line(obj) -> str:
    """First docstring line of ``obj`` as plain reStructuredText text (markup escaped)."""
    doc = (getattr(obj, "__doc__", None) or "").strip().splitlines()
    line = doc[0].strip() if doc else ""
    for ch in "\\*|_`":
        line = line.replace(ch, "\\" + ch)
    return line


def _module_page(name: str, public: set[str]) -> str:
    """reStructuredText of one API page: a package lists its exports, a module documents them."""
    import importlib

    module = importlib.import_module(name)
    lines = [f".. _api-{name}:\n", _title(name, "=")]
    subs = sorted(m for m in public if m.rsplit(".", 1)[0] == name)
    if not subs:
        lines.append(f".. automodule:: {name}\n   :members:\n")
        return "\n".join(lines)
    lines.append(f".. automodule:: {name}\n   :no-members:\n")
    exported = []
    for attr in getattr(module, "__all__", []):
        obj = getattr(module, attr, None)
        home = getattr(obj, "__module__", None)
        if home in public and callable(obj):
            summary = _first_line(obj)
            exported.append(f"* :py:obj:`{attr} <{home}.{attr}>` - {summary}"
                            if summary else f"* :py:obj:`{attr} <{home}.{attr}>`")
    if exported:
        lines += [_title(f"Exported by {name}", "-"),
                  f"Importable as ``from {name} import NAME``; each is documented in "
                  "its module.\n", "\n".join(exported) + "\n"]
    lines += [_title("Modules", "-"),
              "\n".join(f"* :py:mod:`{m}` - {_first_line(importlib.import_module(m))}"
                        for m in subs) + "\n"]
    return "\n".join(lines)


def write_api_page(only: str = "") -> None:
    """Write ``docs/generated/api.rst`` and one page per public module under ``api/``.

    Parameters
    ----------
    only : str, optional
        A regular expression; when given, only the modules whose name it
        matches at the start get a page (``GEOTEX_DOCS_API`` in ``conf.py``:
        a quick partial build, e.g. for the test of the built site). Pages
        of modules left out, written by an earlier build, are removed so
        that no page stands outside the toctree.

    Raises
    ------
    re.error
        If ``only`` is not a regular expression.
    """
    names = public_modules()
    public = set(names)
    if only:
        pattern = re.compile(only)
        names = [n for n in names if pattern.match(n)]
    for name in names:
        _write_if_changed(GENERATED / "api" / f"{name}.rst", _module_page(name, public))
    for stale in (GENERATED / "api").glob("*.rst"):
        if stale.stem not in names:
            stale.unlink()
    head = (DOCS / "api.rst").read_text(encoding="utf-8")
    if only:
        note = (".. note::\n\n   A partial build: only the modules whose name "
                f"matches ``{only}`` (``GEOTEX_DOCS_API``).\n\n")
        head = head.replace(".. toctree::", note + ".. toctree::", 1)
    body = "".join(f"   api/{name}\n" for name in names)
    _write_if_changed(GENERATED / "api.rst", head + body)


def example_argv(gallery_conf, script_vars) -> list[str]:
    """Give each gallery example its own output folder (its ``sys.argv[1]``).

    Parameters
    ----------
    gallery_conf : dict
        sphinx-gallery's configuration (unused).
    script_vars : dict
        sphinx-gallery's script variables; ``src_file`` is the example.

    Returns
    -------
    list of str
        The arguments after the script name.
    """
    out = GALLERY_OUT / Path(script_vars["src_file"]).stem
    if out.exists():
        shutil.rmtree(out)
    out.mkdir(parents=True)
    _seen.pop(str(out), None)
    return [str(out)]


# --- sphinx-gallery scraper ---------------------------------------------------------

_seen: dict[str, set[str]] = {}


def output_scraper(block, block_vars, gallery_conf) -> str:
    """Show the pictures and 3D models an example wrote into its output folder.

    Parameters
    ----------
    block : tuple
        The code block just run (unused).
    block_vars : dict
        sphinx-gallery's block variables (``src_file``, ``image_path_iterator``).
    gallery_conf : dict
        sphinx-gallery's configuration.

    Returns
    -------
    str
        reStructuredText: the pictures as figures, each GLB as a viewer.
    """
    from sphinx_gallery.scrapers import figure_rst

    from geotex.viewpage import viewer_element

    stem = Path(block_vars["src_file"]).stem
    out = GALLERY_OUT / stem
    if not out.is_dir():
        return ""
    seen = _seen.setdefault(str(out), set())
    new = sorted(p for p in out.rglob("*") if p.is_file() and str(p) not in seen)
    seen.update(str(p) for p in new)
    images = []
    # pictures are named after the script (NAME.png, NAME_*.png); other PNGs are
    # texture images that belong to a written OBJ
    for png in (p for p in new if p.suffix.lower() == ".png" and p.name.startswith(stem)):
        target = Path(next(block_vars["image_path_iterator"]))
        shutil.copyfile(png, target)
        images.append(str(target))
    rst = figure_rst(images, gallery_conf["src_dir"]) if images else ""
    for glb in (p for p in new if p.suffix.lower() == ".glb"):
        if glb.stat().st_size > MAX_EMBEDDED_GLB:
            continue
        element = viewer_element(glb.read_bytes(), element_id=f"{stem}-{glb.stem}",
                                 height="440px",
                                 caption=f"{glb.name}: drag to turn, scroll to zoom")
        rst += ("\n\n.. raw:: html\n\n" + textwrap.indent(element, "    ") + "\n\n")
    return rst


def setup(app):
    app.connect("builder-inited", _generate)
    app.connect("source-read", _rewrite_links)
    app.add_js_file("geotex-viewer.js", loading_method="defer")
    return {"parallel_read_safe": True, "parallel_write_safe": True}
