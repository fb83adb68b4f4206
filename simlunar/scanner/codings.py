"""Structured-light codings as plug-ins: one registry entry per coding, carrying its options.

A *coding* is what a projector projects and how the camera frames are decoded into projector
coordinates: the gray code (:mod:`simlunar.scanner.gray_code`), N-step phase shifting with
temporal unwrapping (:mod:`simlunar.scanner.phase_shift`). ``CODINGS`` maps each name to
``Entry(coding class, options class)``; ``meta["yaml_key"]`` names its options block
under a scanner study's ``options`` (``gray_opts``); ``meta["full_field"]`` says whether the coding
measures every lit camera pixel at once (a full-field scan, usable as a scan mode of its own
and under the dot rescans of ambiguity enhancement), ``meta["label"]`` / ``meta["style"]``
how figures name and draw it.

A coding class is built from its options object (``Coding(options)``) and has::

    ``full_field`` : bool
    ``frames(proj_shape) -> int``
        Frames a scan captures (the stack the decoder reads, white and black included): what the
        memory budget of a scan is sized by (:mod:`simlunar.pipeline.preflight`).
    ``frame_names(proj_shape) -> list[str]``, ``frame_order`` : str
        Names and order of the exported frames (:mod:`simlunar.results.exports`).
    ``patterns(proj_shape) -> (frames, H, W) float32 in [0, 1]``
        The projected stack in export order.
    ``decode(frames, proj_shape)``
        The decode of a captured stack in that order (white and black last).
    ``scan(capture, rig, *, keep_frames=False) -> CodedScan``
        Capture, decode, triangulate (:class:`simlunar.scanner.result.CodedScan`); the decode has
        ``valid``, ``lit``, ``contrast``, ``col``, ``row``, ``proj_shape``, ``proj_uv()`` and
        ``decoded_index()``.
    ``method`` : "plane" or "rays" (how its correspondences are triangulated)
    ``export_meta(decode) -> dict``
        Plain data describing the scan for the export manifest.
    ``truth_scores(scan, truth) -> dict[str, float]``
        Decode error rates against camera ground truth (``truth`` from
        :func:`simlunar.render.capture.camera_truth`).

Adding a coding: its module (patterns, decoder, options class, coding class), one
``CODINGS.register`` line here, tests and docs (CONTRIBUTING.md, "Adding a coding").
"""

from __future__ import annotations

from simlunar.registry import Registry
from simlunar.scanner.binary_code import BinaryCodeOptions
from simlunar.scanner.gray_code import GrayCodeOptions, GrayCoding
from simlunar.scanner.micro_phase_shift import MicroPhaseShiftCoding, MicroPhaseShiftOptions
from simlunar.scanner.phase_shift import PhaseShiftCoding, PhaseShiftOptions

__all__ = [
    "CODINGS",
    "DEFAULT_CODING",
    "coding_for",
    "full_field_codings",
    "make_coding",
]

#: coding name -> Entry(coding class, options class); meta: full_field, label, style
CODINGS = Registry("coding")
CODINGS.register(
    "gray_code",
    GrayCoding,
    GrayCodeOptions,
    summary="binary-reflected gray code, OpenCV GrayCodePattern order (paper section 5)",
    full_field=True,
    yaml_key="gray_opts",
    label="Gray code",
    style=("#393b79", "o"),
)
CODINGS.register(
    "phase_shift",
    PhaseShiftCoding,
    PhaseShiftOptions,
    summary="N-step phase shift, multi-frequency temporal unwrapping",
    full_field=True,
    yaml_key="phase_opts",
    label="Phase shift",
    style=("#3182bd", "p"),
)
CODINGS.register(
    "micro_phase_shift",
    MicroPhaseShiftCoding,
    MicroPhaseShiftOptions,
    summary="micro phase shifting: F frequencies in one narrow high band (Gupta & Nayar 2012)",
    full_field=True,
    yaml_key="micro_phase_opts",
    label="Micro phase shift",
    style=("#6baed6", "h"),
)
CODINGS.register(
    "binary",
    GrayCoding,
    BinaryCodeOptions,
    summary="plain binary code through the gray code's decoder (the gray code's counter-example)",
    full_field=True,
    yaml_key="binary_opts",
    label="Binary code",
    style=("#9c9ede", "s"),
)

#: the full-field coding of a scanner whose options name none (the paper's)
DEFAULT_CODING = CODINGS.names()[0]


def full_field_codings() -> tuple[str, ...]:
    """Names of the codings that measure every lit camera pixel in one scan."""
    return tuple(n for n, e in CODINGS.items() if e.meta.get("full_field"))


def make_coding(name: str, options=None):
    """The coding ``name`` built from its options object, a mapping of its fields or None.

    Raises
    ------
    ValueError
        Unknown coding or option name (listing the valid ones), wrong options type.
    """
    entry, options = CODINGS.resolve(name, options)
    return entry.target(options)


def coding_for(options_by_name, name: str):
    """The coding ``name`` with its options from ``options_by_name`` (a mapping name ->
    options object; a coding not in it gets its defaults)."""
    return make_coding(name, (options_by_name or {}).get(name))
