"""The layer rules written in CONTRIBUTING.md, checked on the source."""

from __future__ import annotations

import ast
import importlib
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


# package -> packages it must not import (CONTRIBUTING.md): the study protocol returns numbers
# (tables and figures are plotting's), the scanner measures the pixels it is given (the
# planner chooses them in the study), and the LIDAR acquisitions on arrays are handed their
# rendered capture (ARCHITECTURE: lidar sits below render)
FORBIDDEN = {
    "study": {"plotting", "pipeline", "results", "config"},
    "scanner": {"planner"},
    "lidar": {"render"},
}


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


# --------------------------------------------------------------------------- test modules
TESTS = Path(__file__).resolve().parent

#: library modules without a test module of their own (``tests/<package>/test_<module>.py``,
#: ``tests/test_<module>.py`` for a top-level module). The list only shrinks: a new module
#: comes with its test module, and a module that gains one leaves the list.
WITHOUT_OWN_TEST = [
    "render/beams.py",
    "render/capture.py",
    "render/plugins/hapke.py",
    "render/plugins/oren_nayar.py",
]


def _library_modules(pkg: Path) -> list[Path]:
    """The package's modules: every ``.py`` but packages' ``__init__``, ``__main__`` and
    private ``_*.py`` helpers."""
    return sorted(
        p for p in pkg.rglob("*.py") if "__pycache__" not in p.parts and not p.name.startswith("_")
    )


def _without_own_test(pkg: Path, tests: Path) -> list[str]:
    """Modules of ``pkg`` (paths relative to it) that lack ``tests/<package>/test_<module>.py``."""
    return [
        str(p.relative_to(pkg))
        for p in _library_modules(pkg)
        if not (tests / p.relative_to(pkg).parent / f"test_{p.stem}.py").is_file()
    ]


def test_every_library_module_has_a_test_module_of_its_own():
    missing = _without_own_test(PKG, TESTS)
    new = sorted(set(missing) - set(WITHOUT_OWN_TEST))
    assert new == [], f"modules without tests/<package>/test_<module>.py: {new}"
    gained = sorted(set(WITHOUT_OWN_TEST) - set(missing))
    assert gained == [], (
        f"these have a test module now (or are gone): drop them from WITHOUT_OWN_TEST: {gained}"
    )
    assert WITHOUT_OWN_TEST == sorted(set(WITHOUT_OWN_TEST))


def test_the_test_module_check_sees_missing_and_misplaced_tests(tmp_path):
    pkg, tests = tmp_path / "simlunar", tmp_path / "tests"
    for f in ("__init__.py", "a.py", "_private.py", "sub/__init__.py", "sub/b.py", "sub/c.py"):
        (pkg / f).parent.mkdir(parents=True, exist_ok=True)
        (pkg / f).write_text("")
    (tests / "sub").mkdir(parents=True)
    (tests / "test_a.py").write_text("")
    (tests / "test_b.py").write_text("")  # not in tests/sub/: not b's own
    (tests / "sub" / "test_c.py").write_text("")
    assert _without_own_test(pkg, tests) == ["sub/b.py"]


# --------------------------------------------------------------------------- __all__
def _all_of(tree: ast.Module, module: str):
    """A module's ``__all__`` (None without one): its literal value, or where it is computed
    (``simlunar.render``'s lazy exports) the imported module's."""
    for node in tree.body:
        targets = node.targets if isinstance(node, ast.Assign) else [getattr(node, "target", None)]
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and any(
            getattr(t, "id", None) == "__all__" for t in targets
        ):
            try:
                value = ast.literal_eval(node.value)
            except ValueError:
                value = importlib.import_module(module).__all__
            if not isinstance(value, (list, tuple)) or not all(isinstance(v, str) for v in value):
                raise ValueError("__all__ is not a list of names")
            return list(value)
    return None


def _bound_names(tree: ast.Module) -> set[str]:
    """Names a module binds at its top level (definitions, assignments, imports, also inside
    top-level if / try / with / for blocks)."""
    names: set[str] = set()
    todo = list(tree.body)
    while todo:
        node = todo.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
            continue
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            names |= {(a.asname or a.name).split(".")[0] for a in node.names}
            continue
        targets = []
        if isinstance(node, ast.Assign):
            targets = node.targets
        elif isinstance(node, (ast.AnnAssign, ast.AugAssign, ast.For, ast.AsyncFor)):
            targets = [node.target]
        elif isinstance(node, (ast.With, ast.AsyncWith)):
            targets = [i.optional_vars for i in node.items if i.optional_vars is not None]
        for t in targets:
            names |= {n.id for n in ast.walk(t) if isinstance(n, ast.Name)}
        for field in ("body", "orelse", "finalbody", "handlers"):
            todo.extend(getattr(node, field, []))
    return names


def _all_problems(pkg: Path) -> list[str]:
    """Modules and packages of ``pkg`` without ``__all__`` or with a name in it that the module
    does not bind (private ``_*.py`` helpers and ``__main__`` aside)."""
    out = []
    for p in sorted(pkg.rglob("*.py")):
        if "__pycache__" in p.parts or (p.name.startswith("_") and p.name != "__init__.py"):
            continue
        tree = ast.parse(p.read_text(), filename=str(p))
        rel = str(p.relative_to(pkg))
        module = ".".join((pkg.name, *p.relative_to(pkg).with_suffix("").parts))
        module = module.removesuffix(".__init__")
        try:
            names = _all_of(tree, module)
        except ValueError:
            out.append(f"{rel}: __all__ is not a list of names")
            continue
        if names is None:
            out.append(f"{rel}: no __all__")
            continue
        bound = _bound_names(tree)
        if "__getattr__" in bound:  # a lazy module: its names appear when asked for
            mod = importlib.import_module(module)
            bound |= {n for n in names if hasattr(mod, n)}
        unbound = [n for n in names if n not in bound]
        if unbound:
            out.append(f"{rel}: __all__ names what it does not define: {unbound}")
        if len(set(names)) != len(names):
            out.append(f"{rel}: __all__ names something twice")
    return out


def test_every_module_and_package_has_an_all_of_names_it_defines():
    assert _all_problems(PKG) == []


def test_the_all_check_sees_missing_and_undefined_names(tmp_path):
    pkg = tmp_path / "simlunar"
    pkg.mkdir()
    files = {
        "__init__.py": "",
        "ok.py": "import numpy as np\nfrom x import y as z\n__all__ = ['f', 'C', 'K', 'z', 'np']\n"
        "def f(): pass\nclass C: pass\ntry:\n    K = 1\nexcept ImportError:\n    K = 2\n",
        "bad.py": "__all__ = ['f', 'gone']\ndef f(): pass\n",
        "twice.py": "__all__ = ['f', 'f']\ndef f(): pass\n",
        "numbers.py": "__all__ = [1, 2]\n",
        "_private.py": "",
        "__main__.py": "",
    }
    for name, text in files.items():
        (pkg / name).write_text(text)
    assert _all_problems(pkg) == [
        "__init__.py: no __all__",
        "bad.py: __all__ names what it does not define: ['gone']",
        "numbers.py: __all__ is not a list of names",
        "twice.py: __all__ names something twice",
    ]
