"""The architecture's layer rules (../shared/ARCHITECTURE.md), checked on the source."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "simlunar"

# module prefix -> the only subpackage allowed to import it
RULES = {
    "yaml": "config",
    "mitsuba": "render",
    "drjit": "render",
    "mitransient": "render",
    "matplotlib": "plotting",
}


def _imports(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("module, owner", sorted(RULES.items()))
def test_only_the_owning_package_imports(module, owner):
    offenders = [
        str(p.relative_to(PKG))
        for p in PKG.rglob("*.py")
        if p.relative_to(PKG).parts[0] != owner and module in _imports(p)
    ]
    assert offenders == [], f"{module} imported outside simlunar/{owner}: {offenders}"


def test_the_rule_check_sees_imports(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("def f():\n    import matplotlib.pyplot as plt\n    from drjit import llvm\n")
    assert {"matplotlib", "drjit"} <= _imports(f)


def _own_imports(path: Path) -> set[str]:
    """simlunar packages a module imports (module level and inside functions)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    names = set()
    for node in ast.walk(tree):
        mods = []
        if isinstance(node, ast.Import):
            mods = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            mods = [node.module]
        names |= {m.split(".")[1] for m in mods if m.startswith("simlunar.")}
    return names


# package -> packages it must not import (ARCHITECTURE.md): the study protocol returns numbers
# (tables and figures are plotting's), and the scanner measures the pixels it is given (the
# planner chooses them in the study)
FORBIDDEN = {"study": {"plotting", "pipeline", "results", "config"}, "scanner": {"planner"}}


@pytest.mark.parametrize("package, forbidden", sorted(FORBIDDEN.items()))
def test_package_does_not_import(package, forbidden):
    offenders = sorted(
        f"{p.relative_to(PKG)} -> {', '.join(sorted(_own_imports(p) & forbidden))}"
        for p in (PKG / package).rglob("*.py")
        if _own_imports(p) & forbidden
    )
    assert offenders == []


def test_the_package_rule_sees_function_level_imports(tmp_path):
    f = tmp_path / "m.py"
    f.write_text("def f():\n    from simlunar.planner import plan\n")
    assert _own_imports(f) == {"planner"}
