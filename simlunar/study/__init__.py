"""Studies that run the library's stages end to end on arrays (no files, no YAML)."""

__all__ = []
