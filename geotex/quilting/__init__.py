"""Mesh quilting: synthesize planar geometric textures from an exemplar.

Pipeline (DESIGN.md §5.3 step 4): :func:`quilt_texture` grids the plane,
picks the free cell with the most filled neighbours, places a translated copy
of the exemplar where it matches the texture built so far
(:mod:`~geotex.quilting.match`: matching energy over cell-multiple
translations, then :func:`icp_translation`), and merges corresponding
elements (:mod:`~geotex.quilting.merge`: graph cut with
:func:`min_cut_keep`, Laplacian pull with :func:`laplacian_deformed`,
stitching, exact-boolean fallback).  :class:`QuiltReport` says how good the
result is.
"""

from geotex.quilting.deform import laplacian_deformed
from geotex.quilting.elements import Element, concatenate_elements, split_elements
from geotex.quilting.icp import ClosestPoints, IcpInfo, icp_translation
from geotex.quilting.match import ExemplarIndex, Match, best_translation, matching_energy
from geotex.quilting.elements import closed_element_ok
from geotex.quilting.merge import MergeResult, merge_elements
from geotex.quilting.mincut import MinCut, min_cut, min_cut_keep
from geotex.quilting.quality import QuiltReport, coverage_fraction, quilt_report
from geotex.quilting.quilt import QuiltResult, default_cell, quilt_texture

__all__ = [
    "quilt_texture", "QuiltResult", "QuiltReport", "quilt_report", "default_cell",
    "coverage_fraction",
    "min_cut", "min_cut_keep", "MinCut",
    "icp_translation", "IcpInfo", "ClosestPoints",
    "laplacian_deformed",
    "ExemplarIndex", "Match", "best_translation", "matching_energy",
    "merge_elements", "MergeResult", "closed_element_ok",
    "Element", "split_elements", "concatenate_elements",
]
