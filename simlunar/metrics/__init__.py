"""simlunar.metrics"""
