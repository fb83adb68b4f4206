"""Registers simlunar's Mitsuba plugins once the variant is set (see backend.init)."""

from __future__ import annotations

import simlunar.render.bsdfs  # noqa: F401  (registers oren_nayar and hapke)
