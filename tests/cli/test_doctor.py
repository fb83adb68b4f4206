"""``simlunar doctor``: the variant and why, in one line or in full; a bad SIMLUNAR_VARIANT is one
error line (exit 2). The scalar variant is forced so that nothing is probed."""

from __future__ import annotations

import os

from typer.testing import CliRunner

from simlunar.cli import app


def _doctor(*args, variant="scalar_rgb"):
    return CliRunner().invoke(app, ["doctor", *args], env={"SIMLUNAR_VARIANT": variant})


def test_short_is_one_line():
    r = _doctor("--short")
    assert r.exit_code == 0, r.output
    assert r.stdout == "simlunar doctor: variant scalar_rgb (forced by SIMLUNAR_VARIANT/prefer)\n"


def test_the_full_report():
    r = _doctor()
    assert r.exit_code == 0, r.output
    lines = r.stdout.splitlines()
    assert lines[0] == "simlunar doctor"
    rows = {line[2:17].strip(): line[18:] for line in lines[1:]}
    assert rows["variant"] == "scalar_rgb"
    assert rows["why"] == "forced by SIMLUNAR_VARIANT/prefer"
    assert rows["libLLVM"] == "none"  # the forced scalar variant looks for none
    assert rows["cores"] == str(os.cpu_count())
    assert rows["simlunar"] == "0.1.0" and rows["python"]
    assert rows["GPU"] in ("none", "CUDA device present")
    assert {"numpy", "mitsuba", "drjit", "kernel cache", "machine"} <= set(rows)


def test_an_unknown_variant_is_one_error_line():
    r = _doctor("--short", variant="vulkan_rgb")
    assert r.exit_code == 2
    assert r.stderr == (
        "error: SIMLUNAR_VARIANT=vulkan_rgb: unknown variant 'vulkan_rgb'; "
        "valid: cuda_ad_rgb, llvm_ad_rgb, scalar_rgb\n"
    )
