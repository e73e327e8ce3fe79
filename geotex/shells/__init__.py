"""Shells: base solids with their polycube map, ready to receive tiles.

Build one with :func:`build_shell`, save and load with :func:`save_shell` /
:func:`load_shell`, use the catalog shipped with geotex (:func:`list_shells`,
:func:`shell_path`, :func:`load_named`), and map tile points onto the base
with :func:`locate_on_quads` / :func:`quad_points_to_shell`.
"""

from geotex.shells.build import (SHELL_STAGES, Shell, bare_area, bare_warning, build_shell,
                                 max_offset_height, offset_directions)
from geotex.shells.catalog import list_shells, load_named, shell_path
from geotex.shells.scale import scaled_shell
from geotex.shells.locate import locate_on_quads, quad_points_to_base, quad_points_to_shell
from geotex.shells.store import load_shell, save_shell

__all__ = ["Shell", "build_shell", "offset_directions", "max_offset_height", "SHELL_STAGES",
           "bare_area", "bare_warning", "save_shell", "load_shell", "list_shells", "shell_path", "load_named",
           "locate_on_quads", "quad_points_to_base", "quad_points_to_shell", "scaled_shell"]
