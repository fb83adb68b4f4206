"""libLLVM discovery: versions read off file names, the search order (env, the environment's
PyPI LLVM, the system), old or missing libraries skipped, never loaded."""

from __future__ import annotations

import os

import pytest

from simlunar.render import llvm


def test_llvm_version_from_file_names():
    assert llvm.llvm_major_from_name("/usr/lib/x86_64-linux-gnu/libLLVM-19.so") == 19
    assert llvm.llvm_major_from_name("/venv/lib/libLLVM.so.23.1") == 23
    assert llvm.llvm_major_from_name("libLLVM-15.so.1") == 15
    assert llvm.llvm_major_from_name("libfoo.so") is None
    assert not llvm.LLVMCandidate("x", 15, "system").usable
    assert llvm.LLVMCandidate("x", 16, "system").usable


def test_env_override_is_searched_first(monkeypatch, tmp_path):
    lib = tmp_path / "libLLVM-42.so"
    lib.write_bytes(b"")
    monkeypatch.setenv("DRJIT_LIBLLVM_PATH", str(lib))
    cands = llvm.candidates()
    assert cands[0].path == str(lib) and cands[0].source == "env" and cands[0].major == 42


def _cands(monkeypatch, *cands):
    monkeypatch.setattr(llvm, "candidates", lambda: list(cands))


def test_find_skips_missing_and_old_libraries(monkeypatch, tmp_path):
    old = tmp_path / "libLLVM-15.so"
    new = tmp_path / "libLLVM-18.so"
    unnamed = tmp_path / "libLLVM.so"
    for f in (old, new, unnamed):
        f.write_bytes(b"")
    _cands(
        monkeypatch,
        llvm.LLVMCandidate(str(tmp_path / "libLLVM-20.so"), 20, "env"),  # not on disk
        llvm.LLVMCandidate(str(old), 15, "pypi"),
        llvm.LLVMCandidate(str(new), 18, "system"),
    )
    assert llvm.find_libllvm().path == str(new)
    # a library whose version the name does not tell is tried (the probe decides)
    _cands(monkeypatch, llvm.LLVMCandidate(str(unnamed), None, "system"))
    assert llvm.find_libllvm().path == str(unnamed)
    _cands(monkeypatch, llvm.LLVMCandidate(str(old), 15, "system"))
    assert llvm.find_libllvm() is None


def test_main_prints_the_best_or_says_why_none(monkeypatch, tmp_path, capsys):
    lib = tmp_path / "libLLVM-17.so"
    lib.write_bytes(b"")
    _cands(monkeypatch, llvm.LLVMCandidate(str(lib), 17, "env"))
    assert llvm.main() == 0
    assert capsys.readouterr().out == f"{lib}\n"
    _cands(monkeypatch, llvm.LLVMCandidate("/x/libLLVM-14.so", 14, "system"))
    assert llvm.main() == 1
    assert capsys.readouterr().err == (
        "no usable libLLVM >= 16 found; candidates: /x/libLLVM-14.so (LLVM 14)\n"
    )
    _cands(monkeypatch)
    assert llvm.main() == 1
    assert capsys.readouterr().err.endswith("candidates: none\n")


def test_pypi_llvm_of_this_environment_newest_first_links_skipped(monkeypatch, tmp_path):
    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "libLLVM.so.19.1").write_bytes(b"")
    (lib / "libLLVM.so.23.1").write_bytes(b"")
    os.symlink(lib / "libLLVM.so.23.1", lib / "libLLVM.so.23")
    monkeypatch.setattr(llvm.sys, "prefix", str(tmp_path))
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
    pypi = [c for c in llvm.candidates() if c.source == "pypi"]
    assert [(os.path.basename(c.path), c.major) for c in pypi][:2] == [
        ("libLLVM.so.23.1", 23),
        ("libLLVM.so.19.1", 19),
    ]
    assert all(not os.path.islink(c.path) for c in pypi)


@pytest.mark.parametrize("name", ["libLLVM-16.so", "libLLVM.so.16", "libLLVM.so.16.0.6"])
def test_the_oldest_usable_version(name):
    c = llvm.LLVMCandidate(name, llvm.llvm_major_from_name(name), "system")
    assert c.major == llvm.MIN_LLVM_MAJOR == 16 and c.usable
