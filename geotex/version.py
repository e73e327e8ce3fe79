"""The package version: one definition, read by pyproject.toml (setuptools ``attr``),
``geotex.__version__``, the CLI's ``--version`` and the files geotex writes."""

__all__ = ["VERSION"]

VERSION = "0.1.0"
