"""The tile set catalog: files, recipes, byte-identical rebuild, listing."""

from __future__ import annotations

import numpy as np
import pytest

from geotex.cli import main
from geotex.tiles import list_tilesets, load_named, save_tileset
from geotex.tiles.catalog import CATALOG_DIR, MAX_BYTES, rebuild, recipes
from geotex.tiles.verify import check_seams


def test_catalog_has_closed_object_sets_within_the_size_limit():
    entries = list_tilesets()
    closed = [e for e in entries if e["kind"] in ("isotropic", "complete")]
    assert len(closed) >= 4
    assert any(e["kind"] == "complete" and e["tiles"] == 96 for e in entries)
    assert sum(e["kind"] == "isotropic" and e["tiles"] == 16 for e in entries) >= 3
    assert len({e["exemplar"] for e in closed}) >= 3
    for e in entries:
        assert 0 < e["bytes"] <= MAX_BYTES, e["name"]


@pytest.mark.parametrize("name", sorted(recipes()))
def test_catalog_set_matches_its_recipe_and_is_seamless(name):
    r = recipes()[name]
    ts = load_named(name)
    assert ts.name == name and len(ts) == r["tiles"]
    assert ts.kind == ("directional" if r.get("directional") else
                       "isotropic" if r["isotropic"] else
                       "planar" if r["planar"] else "complete")
    assert ts.isotropic == r["isotropic"]
    assert ts.metadata["recipe"]["seed"] == r["seed"]
    assert ts.metadata["recipe"]["interior"] == r["interior"]
    # linked chain mail and the weave are cut from their periodic layouts (rings
    # picked one by one would not be linked, strands longer than a tile could not
    # be picked at all); every other set is quilted
    assert r["interior"] == ("periodic" if name in ("chainmail", "weave") else "quilt")
    assert ts.metadata["exemplar"]["params"] == r["exemplar"]["params"]
    if r["interior"] == "quilt":
        assert ts.metadata["paste_fallbacks"] <= len(ts) // 8
    rep = check_seams(ts)
    assert rep.ok, rep.problems[:3]
    for pic in r["pictures"]:
        assert pic.startswith("docs/gallery/tiles_") and pic.endswith(".png")


def test_rebuild_from_recipe_is_byte_identical(tmp_path):
    # the catalog set with the fewest tiles, rebuilt from its recipe by the same
    # code path as `python -m geotex.tiles.catalog NAME`
    name = min(recipes(), key=lambda n: (recipes()[n]["tiles"], n))
    assert recipes()[name]["interior"] == "quilt"
    out = tmp_path / f"{name}.npz"
    save_tileset(out, rebuild(name))
    shipped = (CATALOG_DIR / f"{name}.npz").read_bytes()
    assert out.read_bytes() == shipped, (
        f"{name} no longer rebuilds byte for byte; if the change is wanted, run "
        f"python -m geotex.tiles.catalog {name}")


def test_chainmail_rebuilds_byte_identical_and_holds_linked_rings(tmp_path):
    # the periodic set builds in a second, so it is rebuilt here too
    out = tmp_path / "chainmail.npz"
    ts = rebuild("chainmail")
    save_tileset(out, ts)
    assert out.read_bytes() == (CATALOG_DIR / "chainmail.npz").read_bytes()
    assert ts.metadata["periodic"]["layout"] == "diagonal 4-in-1"
    assert "linked" in recipes()["chainmail"]["description"]


def test_weave_rebuilds_byte_identical_and_runs_strands_across_sides(tmp_path):
    out = tmp_path / "weave.npz"
    ts = rebuild("weave")
    save_tileset(out, ts)
    assert out.read_bytes() == (CATALOG_DIR / "weave.npz").read_bytes()
    assert ts.metadata["periodic"]["layout"] == "plain weave"
    assert ts.metadata["tiling_border"] == "cap"
    assert "weave" in recipes()["weave"]["description"]


def test_catalog_names_and_cli_list(capsys):
    assert main(["tiles", "list"]) == 0
    out = capsys.readouterr().out
    for r in list_tilesets():
        line = next(ln for ln in out.splitlines() if ln.startswith(r["name"] + " "))
        assert r["kind"] in line and str(r["tiles"]) in line
    assert "isotropic" in out and "complete" in out
    assert main(["tiles", "check", "studs"]) == 0
    assert "seamless" in capsys.readouterr().out
    assert main(["tiles", "check", "no-such-set"]) == 2
    err = capsys.readouterr().err
    assert "catalog:" in err and err.count("\n") == 1


def test_catalog_tiling_is_printable(tmp_path, capsys):
    out = tmp_path / "knurl.stl"
    assert main(["tiles", "tile", "knurl", "--grid", "3", "3", "-o", str(out),
                 "--seed", "2"]) == 0
    assert "printable" in capsys.readouterr().out and out.stat().st_size > 10_000
    ts = load_named("studs-complete")
    # every group of a complete set is present, 16 tiles each
    groups, counts = np.unique(ts.groups, axis=0, return_counts=True)
    assert len(groups) == 6 and set(counts.tolist()) == {16}
