"""simlunar.planner"""
