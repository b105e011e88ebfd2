"""pincal's version (the one in pyproject.toml), importable by every stage."""

__version__ = "0.1.0"
