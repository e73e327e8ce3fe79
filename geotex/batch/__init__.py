"""Batch jobs on Dask: a folder or manifest of parts, on one machine or a cluster.

>>> from geotex.batch import read_parts, run            # doctest: +SKIP
>>> rows = run("parts.csv", job="texture", tiles="studs", outdir="out")   # doctest: +SKIP
>>> [r["status"] for r in rows]                          # doctest: +SKIP
['ok', 'failed', 'ok']

:mod:`~geotex.batch.manifest` reads parts, :mod:`~geotex.batch.jobs` holds the
job table, :mod:`~geotex.batch.run` is the Dask engine and
:mod:`~geotex.batch.summary` writes ``summary.csv`` / ``summary.json``.
"""

from geotex.batch.jobs import JOBS, Job
from geotex.batch.manifest import COLUMNS, Part, folder_parts, read_manifest, read_parts
from geotex.batch.run import default_workers, local_cluster, run, run_part
from geotex.batch.summary import FIELDS, read_summary, write_summary

__all__ = ["run", "run_part", "local_cluster", "default_workers", "Part", "read_parts",
           "read_manifest", "folder_parts", "COLUMNS", "JOBS", "Job", "FIELDS",
           "write_summary", "read_summary"]
