"""A ``study.reconstructions`` item read in one place: its label, its registered
reconstruction and its options, the same for every reader (validation, translation, the
protocol, row order, aggregation, cache-key versions)."""

from __future__ import annotations

import pytest

from simlunar.config.derived import reconstruction_mapping, reconstruction_specs
from simlunar.reconstruction import RECONSTRUCTIONS, LinearOptions
from simlunar.results.aggregate import reconstruction_names
from simlunar.results.cache_keys import reconstruction_versions
from simlunar.study.protocol import reconstruction_options
from simlunar.study.reconstruction_spec import ReconstructionSpec, parse_reconstructions

ITEMS = [
    "linear",
    {"smoothed": {"sigma_pitch": 0.75}},
    {"linear_nan": {"reconstruction": "linear", "outside": "nan"}},
]


def test_each_shape_of_an_item_gives_its_label_name_and_options():
    plain, opts, labelled = parse_reconstructions(ITEMS)
    assert (plain.label, plain.name, dict(plain.options)) == ("linear", "linear", {})
    assert (opts.label, opts.name, dict(opts.options)) == ("smoothed", "smoothed",
                                                            {"sigma_pitch": 0.75})  # fmt: skip
    assert (labelled.label, labelled.name, dict(labelled.options)) == (
        "linear_nan", "linear", {"outside": "nan"}
    )  # fmt: skip
    assert [s.labelled for s in (plain, opts, labelled)] == [False, False, True]
    # written back as given (a mapping without options is the name alone)
    assert [s.item() for s in (plain, opts, labelled)] == ITEMS
    assert ReconstructionSpec.parse({"linear": None}).item() == "linear"
    assert ReconstructionSpec.parse({"linear": {}}).item() == "linear"
    assert labelled.values() == {"reconstruction": "linear", "outside": "nan"}
    assert parse_reconstructions(None) == []


@pytest.mark.parametrize(
    ("item", "problem"),
    [
        ({"linear": {}, "smoothed": {}}, "one name or one"),
        ({"linear": 3}, "options must be a mapping"),
        ({"": {}}, "non-empty name"),
        (7, "non-empty name"),
        ({"x": {"reconstruction": 5}}, "unknown reconstruction 5"),
    ],
)
def test_a_malformed_item_is_refused(item, problem):
    with pytest.raises(ValueError, match=problem):
        ReconstructionSpec.parse(item)


def test_every_reader_sees_the_same_labels_and_reconstructions(monkeypatch):
    specs = reconstruction_specs(ITEMS)  # the schema's validation
    assert specs == ITEMS
    mapping = reconstruction_mapping(specs)  # the translation into the studies' options
    assert mapping == {"linear": {}, "smoothed": {"sigma_pitch": 0.75},
                       "linear_nan": {"reconstruction": "linear", "outside": "nan"}}  # fmt: skip
    labels = ["linear", "smoothed", "linear_nan"]
    assert reconstruction_names({"reconstructions": specs}) == labels  # aggregation
    built = reconstruction_options(mapping)  # the protocol
    assert list(built) == labels and isinstance(built["linear_nan"], LinearOptions)
    assert built["linear_nan"].outside == "nan" and built["linear"].outside == "nearest"
    # the protocol takes the items (or specs) themselves too, to the same options
    assert reconstruction_options(ITEMS) == built
    assert reconstruction_options(parse_reconstructions(ITEMS)) == built
    # the cache key's method versions follow the registered name, not the label
    monkeypatch.setitem(RECONSTRUCTIONS["linear"].meta, "results_version", 2)
    assert reconstruction_versions({"reconstructions": [ITEMS[2]]}) == {"linear": 2}
    assert reconstruction_versions({"reconstructions": [ITEMS[1]]}) == {}
