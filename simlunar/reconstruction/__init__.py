"""simlunar.reconstruction"""
