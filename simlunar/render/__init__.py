"""Rendering with Mitsuba 3: the only package of simlunar that imports mitsuba or drjit.

Importing this package does not import Mitsuba; :func:`simlunar.render.backend.init` does.
"""
