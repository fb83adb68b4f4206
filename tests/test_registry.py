"""The generic registry: one entry per component, name and option checks derived from it."""

from dataclasses import dataclass

import numpy as np
import pytest

from simlunar.registry import (
    Options,
    Registry,
    UnknownNameError,
    build_options,
    check_bounds,
    did_you_mean,
    option,
    option_docs,
    option_info,
    shared_option,
)


@dataclass(frozen=True)
class _Opts:
    gain: float = option(1.0, doc="a gain", ge=0.0, le=4.0)
    sigma: float = option(2.0, doc="a width", unit="cell", gt=0.0)
    mode: str = option("a", doc="a mode", choices=("a", "b"))

    def __post_init__(self):
        check_bounds(self)


def test_unknown_name_lists_valid_and_suggests_the_closest():
    reg = Registry("widget")
    reg.register("shading", print, _Opts)
    reg.register("linear", print, _Opts)
    with pytest.raises(
        ValueError,
        match=r"unknown widget 'shadng'; valid: shading, linear \(did you mean 'shading'\?\)",
    ):
        reg["shadng"]
    with pytest.raises(KeyError):  # a mapping too
        reg["nothing"]
    assert "linear" in reg and "x" not in reg
    assert list(reg) == ["shading", "linear"] and len(reg) == 2


def test_a_name_is_registered_once_and_options_must_be_a_dataclass():
    reg = Registry("widget")
    reg.register("a", print, _Opts)
    with pytest.raises(ValueError, match="registered twice"):
        reg.register("a", print, _Opts)
    with pytest.raises(TypeError, match="must be a dataclass"):
        reg.register("b", print, dict)


def test_resolve_builds_or_checks_the_options_object():
    reg = Registry("widget")
    reg.register("a", print, _Opts)
    entry, opts = reg.resolve("a")
    assert entry.name == "a" and opts == _Opts()
    assert reg.resolve("a", {"gain": 3.0})[1] == _Opts(gain=3.0)
    given = _Opts(sigma=5.0)
    assert reg.resolve("a", given)[1] is given
    with pytest.raises(TypeError, match="widget 'a' takes _Opts, got str"):
        reg.resolve("a", "gain=3")
    with pytest.raises(ValueError, match="gain must be <= 4"):
        reg.resolve("a", {"gain": 9.0})
    with pytest.raises(UnknownNameError, match="unknown widget 'b'"):
        reg.resolve("b")


def test_stray_option_key_is_refused_with_a_suggestion():
    with pytest.raises(
        UnknownNameError,
        match=r"unknown option 'gian' of x; valid: gain, sigma, mode \(did you mean 'gain'\?\)",
    ):
        build_options(_Opts, {"gian": 1.0}, what="x")
    assert build_options(_Opts, {"gain": 2.0}).gain == 2.0
    assert build_options(_Opts, None) == _Opts()


@pytest.mark.parametrize(
    ("kw", "msg"),
    [
        ({"gain": -0.1}, "gain must be >= 0"),
        ({"gain": 4.5}, "gain must be <= 4"),
        ({"sigma": 0.0}, "sigma must be > 0"),
        ({"sigma": float("nan")}, "sigma must be a finite number"),
        ({"gain": True}, "gain must be a finite number"),
        ({"gain": np.bool_(True)}, "gain must be a finite number"),
        ({"sigma": np.float32("nan")}, "sigma must be a finite number"),
        ({"gain": np.int64(5)}, "gain must be <= 4"),
        ({"mode": "c"}, "mode must be one of 'a', 'b'"),
    ],
)
def test_bounds_declared_once_are_checked(kw, msg):
    with pytest.raises(ValueError, match=msg):
        _Opts(**kw)


@dataclass(frozen=True)
class _Band(Options):
    lo: float = option(0.1, doc="lower edge", ge=0)
    hi: float = option(0.5, doc="upper edge", le=1)

    def __post_init__(self):
        super().__post_init__()
        if self.hi <= self.lo:
            raise ValueError("hi must be > lo")


def test_an_options_subclass_checks_its_declared_bounds_on_construction():
    with pytest.raises(ValueError, match="lo must be >= 0, got -1"):
        _Band(lo=-1.0)
    # the bounds first, then the subclass's rule across fields
    with pytest.raises(ValueError, match="hi must be <= 1, got 2"):
        _Band(lo=3.0, hi=2.0)
    with pytest.raises(ValueError, match="hi must be > lo"):
        _Band(lo=0.6, hi=0.5)
    assert _Band(lo=0.2).hi == 0.5 and option_docs(_Band)[2] == "lo : float, default 0.1"


def test_none_passes_the_bounds_only_of_a_field_that_may_hold_it():
    @dataclass(frozen=True)
    class Opt(Options):
        cap: float | None = option(None, doc="a cap (None: none)", gt=0)
        width: float = option(1.0, doc="a width", gt=0)

    assert Opt().cap is None
    # before, None skipped every bound and failed later, far from the option that was wrong
    with pytest.raises(ValueError, match="width must be a finite number, got None"):
        Opt(width=None)


def test_numpy_scalars_are_numbers_to_the_bounds():
    # a value read from an array (float32 image statistics, int64 counts) was refused as
    # "not a finite number" when only Python int and float counted
    assert _Opts(gain=np.float32(2.5), sigma=np.int64(3)).sigma == 3


def test_option_info_carries_doc_unit_bounds_and_default():
    info = option_info(_Opts)
    assert info["sigma"]["unit"] == "cell" and info["sigma"]["gt"] == 0.0
    assert info["gain"]["default"] == 1.0 and info["gain"]["doc"] == "a gain"
    assert info["mode"]["choices"] == ("a", "b")


def test_option_docs_write_each_field_once_as_a_numpydoc_attributes_section():
    # the API reference's text of a field comes from its declaration: doc, default, unit, bounds
    assert option_docs(_Opts) == [
        "Attributes",
        "----------",
        "gain : float, default 1.0",
        "    A gain. >= 0, <= 4.",
        "sigma : float, default 2.0",
        "    A width. Unit cell, > 0.",
        "mode : str, default 'a'",
        "    A mode. One of 'a', 'b'.",
    ]


def test_option_docs_keep_a_leading_symbol_as_written():
    @dataclass(frozen=True)
    class Sym(Options):
        k: float = option(0.02, doc="k, the ionisation ratio", ge=0)
        lam: float = option(1.0, doc="lam_t: smoothness across the light.", ge=0)

    docs = option_docs(Sym)
    assert docs[3] == "    k, the ionisation ratio. >= 0."
    assert docs[5] == "    lam_t: smoothness across the light. >= 0."


def test_option_docs_are_empty_for_a_class_without_declared_options():
    @dataclass(frozen=True)
    class Plain:
        x: float = 1.0

    assert option_docs(Plain) == []


def test_did_you_mean_is_empty_when_nothing_is_close():
    assert did_you_mean("zzzz", ["linear", "shading"]) == ""


def test_did_you_mean_gives_every_equally_close_name():
    from simlunar.registry import did_you_mean

    assert did_you_mean("wavlet", ["random", "wavelet", "grid"]) == " (did you mean 'wavelet'?)"
    # 'aerial_l' is one edit from each: none is picked by its spelling
    assert did_you_mean("aerial_l", ["aerial_1", "aerial_2", "moonyard"]) == (
        " (did you mean 'aerial_1' or 'aerial_2'?)"
    )
    assert did_you_mean("zzz", ["random", "grid"]) == ""
    assert did_you_mean("x", []) == ""


def test_did_you_mean_file_names_the_closest_sibling(tmp_path):
    from simlunar.registry import did_you_mean_file

    (tmp_path / "quickstart.yaml").write_text("")
    (tmp_path / "table1_aerial.yaml").write_text("")
    (tmp_path / "quickstrt.txt").write_text("")  # another suffix: never suggested
    hint = did_you_mean_file(tmp_path / "quickstrt.yaml")
    assert hint == f" (did you mean {str(tmp_path / 'quickstart.yaml')!r}?)"
    assert did_you_mean_file(tmp_path / "nothing_alike.yaml") == ""
    assert did_you_mean_file(tmp_path / "no_dir" / "x.yaml") == ""


def test_shared_option_gives_each_class_its_own_equal_field():
    table = {"gain": {"default": 1.0, "doc": "a gain", "ge": 0.0, "le": 4.0}}

    @dataclass(frozen=True)
    class A:
        gain: float = shared_option(table, "gain")

        def __post_init__(self):
            check_bounds(self)

    @dataclass(frozen=True)
    class B:
        other: int = 3
        gain: float = shared_option(table, "gain")

    assert option_info(A)["gain"] == option_info(B)["gain"]
    assert option_info(A)["gain"]["default"] == 1.0 and option_info(A)["gain"]["le"] == 4.0
    assert table["gain"]["default"] == 1.0  # the table is not consumed
    with pytest.raises(ValueError, match="gain must be <= 4"):
        A(gain=5.0)
    with pytest.raises(KeyError):
        shared_option(table, "gian")
