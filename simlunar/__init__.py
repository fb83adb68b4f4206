"""simlunar: physically based sensor simulation for image-directed range scanning of lunar terrain."""

__all__ = ["__version__"]

__version__ = "0.1.0"
