"""simlunar.plotting"""
