"""CITATION.cff is valid Citation File Format 1.2.0 and names the paper README cites.

The schema is the CFF 1.2.0 JSON schema as shipped in the ``cffconvert`` 2.0.0 wheel on PyPI
(``cffconvert/schemas/1.2.0/schema.json``, SHA-256 0b8d2214...c169b; the same file as
citation-file-format/citation-file-format 1.2.0). ``cffconvert --validate`` itself cannot be a
dev dependency: it pins ``jsonschema<4``, the project's dev extras need ``jsonschema>=4.20``.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import jsonschema
import yaml

ROOT = Path(__file__).resolve().parents[1]
SCHEMA = Path(__file__).resolve().parent / "data" / "cff-1.2.0.schema.json"
SCHEMA_SHA256 = "0b8d22140da702d766df318dcff3a91af2f39521298dcf36d76315fd99cc169b"


def _cff() -> dict:
    return yaml.safe_load((ROOT / "CITATION.cff").read_text())


def test_citation_cff_validates_against_the_cff_1_2_schema():
    assert hashlib.sha256(SCHEMA.read_bytes()).hexdigest() == SCHEMA_SHA256
    schema = json.loads(SCHEMA.read_text())
    jsonschema.Draft7Validator.check_schema(schema)
    errors = sorted(jsonschema.Draft7Validator(schema).iter_errors(_cff()), key=str)
    assert not errors, "\n".join(f"{list(e.absolute_path)}: {e.message}" for e in errors)


def test_the_schema_check_can_fail():
    schema = json.loads(SCHEMA.read_text())
    bad = {**_cff(), "authors": [], "cff-version": "1.1.0"}
    assert list(jsonschema.Draft7Validator(schema).iter_errors(bad))


def test_the_paper_is_cited_alike_in_citation_readme_and_reproduction():
    cff = _cff()
    paper = cff["preferred-citation"]
    assert cff["version"] == __import__("simlunar").__version__
    for doc in ("README.md", "REPRODUCTION.md"):
        text = (ROOT / doc).read_text()
        assert paper["title"] in text, doc
        assert all(a["family-names"] in text for a in paper["authors"]), doc
        assert str(paper["year"]) in text and "Field and Service Robotics" in text, doc
