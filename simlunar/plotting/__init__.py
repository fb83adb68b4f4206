"""simlunar.plotting"""

__all__ = []
