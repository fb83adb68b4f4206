import os

import pytest

from simlunar.render import backend, llvm


def test_old_llvm_is_never_loaded(monkeypatch, tmp_path):
    # Only an LLVM 15 is offered: the chooser must skip it without probing (probing would abort).
    monkeypatch.setattr(
        llvm,
        "candidates",
        lambda: [llvm.LLVMCandidate(str(tmp_path / "libLLVM-15.so"), 15, "system")],
    )
    (tmp_path / "libLLVM-15.so").write_bytes(b"")
    monkeypatch.setattr(backend, "_cuda_present", lambda: False)

    def no_probe(*a, **k):
        raise AssertionError("an LLVM older than 16 must not be probed")

    monkeypatch.setattr(backend, "_probe", no_probe)
    info = backend.choose_variant(cache_dir=tmp_path)
    assert info.variant == "scalar_rgb"
    assert "LLVM 15 < 16" in info.reason


def test_unknown_variant_is_a_clear_error():
    with pytest.raises(ValueError, match="valid: cuda_ad_rgb, llvm_ad_rgb, scalar_rgb"):
        backend.choose_variant("llvm_rgb_typo")


def test_ci_did_not_silently_fall_back_to_scalar(mi):
    """`make setup` installs libLLVM >= 16 wherever it can; a scalar fallback there is a bug.

    Set SIMLUNAR_ALLOW_SCALAR=1 on a machine where no LLVM can be installed.
    """
    info = backend.info()
    if os.environ.get("SIMLUNAR_ALLOW_SCALAR") == "1":
        pytest.skip("scalar fallback explicitly allowed")
    assert info.variant in backend.JIT_VARIANTS, f"fell back to scalar: {info.reason}"
    assert os.environ["DRJIT_CACHE_DIR"] == info.cache_dir
    assert mi.variant() == info.variant


def test_render_thread_limit_round_trips(mi):
    import drjit as dr

    old = backend.set_render_threads(1)
    try:
        assert dr.thread_count() == 1
    finally:
        assert backend.set_render_threads(old) == 1
    assert dr.thread_count() == old
