"""The version of chuteflow, stated once (``pyproject.toml`` reads it from here)."""

__version__ = "0.3.0"
