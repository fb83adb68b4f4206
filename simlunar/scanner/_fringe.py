"""Options the fringe codings share (phase shift, micro phase shift), declared once.

Both read a camera pixel as lit when white - black exceeds ``black_threshold``, project fringes
along both axes or the columns only, and triangulate by the column plane or by rays (which
need the row phase, hence ``axes="both"``).
"""

from __future__ import annotations

from simlunar.registry import check_bounds

__all__ = [
    "FRINGE_AXES",
    "FRINGE_OPTIONS",
    "TRIANGULATIONS",
    "check_fringe_options",
    "check_rays_axes",
]

FRINGE_AXES = ("both", "cols")
TRIANGULATIONS = ("plane", "rays")

FRINGE_OPTIONS: dict[str, dict] = {
    "axes": dict(default="both", doc="fringes along both axes or columns only", choices=FRINGE_AXES),
    "black_threshold": dict(default=0.05, doc="lit: white - black (frame units)", ge=0, le=1),
    "method": dict(
        default="plane", doc="triangulation: column plane or rays (rays need axes both)",
        choices=TRIANGULATIONS,
    ),
}  # fmt: skip
"""name -> keywords of :func:`simlunar.registry.option` (``default`` its first argument), for
:func:`simlunar.registry.shared_option`."""


def check_fringe_options(options, *, whole: str) -> None:
    """All the checks of a fringe coding's options: the declared bounds
    (:func:`~simlunar.registry.check_bounds`), the count option ``whole`` a whole number, and
    :func:`check_rays_axes`. ``ValueError`` naming the first one that fails."""
    check_bounds(options)
    n = getattr(options, whole)
    if int(n) != n:
        raise ValueError(f"{whole} must be a whole number, got {n!r}")
    check_rays_axes(options)


def check_rays_axes(options) -> None:
    """``ValueError`` when ``options.method`` is "rays" without ``axes="both"``."""
    if options.method == "rays" and options.axes != "both":
        raise ValueError("method 'rays' needs the row phase: use axes 'both'")
