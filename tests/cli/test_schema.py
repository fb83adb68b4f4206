"""``simlunar schema``: each document kind's JSON Schema or the Markdown reference, on stdout
or into a file (its folder made); an unknown kind or a folder as --out in one line."""

from __future__ import annotations

import json

import pytest
from typer.testing import CliRunner

from simlunar.cli import app
from simlunar.config.docs import json_schema, reference_markdown


def _invoke(*args):
    return CliRunner().invoke(app, ["schema", *args])


@pytest.mark.parametrize("kind", ["scene", "preset"])
def test_each_kind_prints_its_schema(kind):
    r = _invoke("--kind", kind)
    assert r.exit_code == 0, r.output
    assert json.loads(r.stdout) == json_schema(kind)
    assert r.stdout == json.dumps(json_schema(kind), indent=2) + "\n"


def test_markdown_into_a_new_folder(tmp_path):
    out = tmp_path / "docs" / "reference.md"
    r = _invoke("--markdown", "--out", str(out))
    assert r.exit_code == 0 and r.stdout == ""
    assert out.read_text() == reference_markdown() + "\n"


def test_refusals_are_one_line(tmp_path):
    r = _invoke("--kind", "render")
    assert r.exit_code == 2
    assert (
        r.stderr
        == "error: --kind render: unknown document kind (valid: experiment, scene, preset)\n"
    )
    r = _invoke("--out", str(tmp_path))
    assert r.exit_code == 2
    assert r.stderr == f"error: --out {tmp_path}: is a folder, not a file\n"
