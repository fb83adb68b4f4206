"""simlunar.features"""
