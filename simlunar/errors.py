"""Errors that the CLI reports as one line with exit code 2 (no traceback)."""

from __future__ import annotations

__all__ = [
    "ConfigError",
    "InfrastructureError",
    "NothingMeasuredError",
    "ResultFolderError",
    "RunInterrupted",
    "SimlunarError",
]


class SimlunarError(Exception):
    """A problem with the user's input (configuration, file, option)."""


class ConfigError(SimlunarError, ValueError):
    """An invalid configuration value; the message names the key path."""


class ResultFolderError(SimlunarError):
    """A result folder that cannot be used: not writable, owned by another run or config,
    or holding files that disagree with each other; the message names the path."""


class NothingMeasuredError(SimlunarError, ValueError):
    """A scan measured no pixel (nothing decoded: the projector too faint against the sun,
    thresholds too strict, the camera seeing no projected pixel): the configuration's
    doing, reported in one line (exit 2) during the run; finished units are kept."""


class PlatformGroundedError(SimlunarError, ValueError):
    """A moving platform would reach the ground during a scan (a descent too fast or a scan too
    long for the height it starts at): reported in one line (exit 2) during the run, naming
    when; finished units are kept."""


class InputChangedError(SimlunarError):
    """A file a unit reads changed during the run (after the run hashed it into the unit's
    cache key): the unit is not stored under a key that names other content; the run stops
    in one line, finished units are kept, a rerun computes with the file as it is then."""


class InfrastructureError(Exception):
    """The environment failed during a run (Dask scheduler or workers lost, a write refused
    by the filesystem): not the user's input, not a bug. Finished units are kept."""


class RunInterrupted(KeyboardInterrupt):
    """SIGINT (Ctrl-C) stopped a run; the message says what was kept and how to resume."""
