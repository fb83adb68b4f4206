"""A YAML block derived from an options class runs the class's own rules at load: a rule across
fields (``method: rays`` needs ``axes: both``) is refused by the schema, not in the unit after
``config.yaml`` is written."""

from __future__ import annotations

from dataclasses import dataclass

import pydantic
import pytest

from simlunar.config.fields import options_model
from simlunar.config.scanner import CODING_OPTS
from simlunar.registry import FileOption, Options, option, option_info


@dataclass(frozen=True)
class _Band(Options):
    lo: float = option(0.1, doc="low end", ge=0)
    hi: float = option(0.5, doc="high end", le=1)

    def __post_init__(self):
        super().__post_init__()
        if self.hi <= self.lo:
            raise ValueError(f"hi must be > lo, got {self.hi} <= {self.lo}")


def test_a_rule_across_fields_is_the_schemas():
    model = options_model(_Band, "BandCfg")
    assert model(lo=0.2, hi=0.3).hi == 0.3
    with pytest.raises(pydantic.ValidationError, match=r"hi must be > lo, got 0\.2 <= 0\.3"):
        model(lo=0.3, hi=0.2)


@pytest.mark.parametrize("coding", ["phase_shift", "micro_phase_shift"])
def test_fringe_codings_refuse_rays_with_columns_only(coding):
    _, model = CODING_OPTS[coding]
    assert model(method="rays", axes="both").axes == "both"
    assert model(method="plane", axes="cols").axes == "cols"
    with pytest.raises(pydantic.ValidationError, match="method 'rays' needs the row phase"):
        model(method="rays", axes="cols")


def test_option_info_carries_the_file_marker():
    @dataclass(frozen=True)
    class _WithFile(Options):
        table: str = option("", doc="a lookup table", file="table")
        gain: float = option(1.0, doc="a gain")

    info = option_info(_WithFile)
    assert info["table"]["file"] == FileOption("table") and info["gain"]["file"] is None
    # the derived YAML model keeps the marker where the cache key's walk reads it
    field = options_model(_WithFile, "WithFileCfg").model_fields["table"]
    assert FileOption("table") in field.metadata
