"""Validity of meshes as printable solids: the report and its parts."""

from geotex.check.intersections import self_intersecting_pairs
from geotex.check.report import CheckReport, check_mesh

__all__ = ["CheckReport", "check_mesh", "self_intersecting_pairs"]
