"""simlunar.scanner"""

__all__ = []
