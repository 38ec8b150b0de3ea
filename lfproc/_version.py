"""lfproc's version: one place, light (imported by the package and by provenance records)."""

__version__ = "0.1.0"
