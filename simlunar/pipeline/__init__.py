"""simlunar.pipeline"""
