"""The package version (one place: the root package, the deck header and the provenance read it)."""

__version__ = "0.1.0"
