"""Errors that the CLI reports as one line with exit code 2 (no traceback)."""

from __future__ import annotations


class SimlunarError(Exception):
    """A problem with the user's input (configuration, file, option)."""


class ConfigError(SimlunarError, ValueError):
    """An invalid configuration value; the message names the key path."""
