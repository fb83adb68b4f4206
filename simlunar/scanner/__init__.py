"""simlunar.scanner"""
