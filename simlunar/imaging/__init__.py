"""simlunar.imaging"""
