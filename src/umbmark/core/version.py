"""The version of umbmark (one place: the package and its build read it)."""

__version__ = "0.2.0"
