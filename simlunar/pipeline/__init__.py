"""simlunar.pipeline"""

__all__ = []
