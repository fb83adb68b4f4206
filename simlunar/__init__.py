"""simlunar: physically based sensor simulation for image-directed range scanning of lunar terrain."""

__version__ = "0.1.0"
