"""A small mutation pass: seeded mutants of library modules, each run against its own tests.

Usage::

    python scripts/mutate.py GROUP [--n 40] [--seed 0] [--timeout 120]
    python scripts/mutate.py --list
    python scripts/mutate.py GROUP --only 6,7,11   # those mutants of the sample (re-check survivors)

A mutant is one edit of one module's syntax tree (``ast``): an arithmetic operator swapped
(``+`` <-> ``-``, ``*`` <-> ``/``, ...), a comparison swapped (``<`` <-> ``<=``, ``==`` <->
``!=``, ...), a boolean operator swapped (``and`` <-> ``or``), a numeric constant changed
(``c`` -> ``c + 1``; 0 <-> 1) or a statement deleted (replaced by ``pass``). Every possible
site of a group's modules is listed in a fixed order and ``--n`` of them are drawn with
``--seed``; each mutant is written into a private copy of the package (the worktree is never
touched) and the group's test files run on it (``pytest -x``). A mutant is *killed* when the
tests fail or time out, *survives* when they pass. Docstrings, ``__all__`` and the bodies of
``raise`` statements' messages are not mutated (no test could tell). Prints one line per
mutant and the killed share; survivors are the tests to write next.
"""

from __future__ import annotations

import argparse
import ast
import copy
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: group -> (modules under simlunar/, their test files)
GROUPS = {
    "reconstruction": (
        ["reconstruction/delaunay.py", "reconstruction/_raster.py"],
        ["tests/reconstruction/test_delaunay.py", "tests/reconstruction/test_registry_recon.py",
         "tests/reconstruction/test_point_scan_flags.py"],
    ),
    "metrics": (
        ["metrics/errors.py", "metrics/score.py", "metrics/interior.py", "metrics/hazard.py"],
        ["tests/metrics/test_errors.py", "tests/metrics/test_score.py",
         "tests/metrics/test_interior.py", "tests/metrics/test_hazard.py",
         "tests/metrics/test_smallest_valid_inputs.py"],
    ),
    "placement": (
        ["planner/placement.py"],
        ["tests/planner/test_placement.py", "tests/planner/test_layout_edges_and_defaults.py"],
    ),
    "gray_code": (
        ["scanner/gray_code.py", "scanner/bitcodes.py"],
        ["tests/scanner/test_gray_code.py", "tests/scanner/test_bitcodes.py",
         "tests/scanner/test_binary_code.py", "tests/scanner/test_code_tables_and_frame_levels.py"],
    ),
    "lidar": (
        ["lidar/ranging.py", "lidar/detector.py"],
        ["tests/lidar/test_ranging.py", "tests/lidar/test_detector.py",
         "tests/lidar/test_photon_budget.py", "tests/lidar/test_sub_bin_position.py"],
    ),
}  # fmt: skip

_BINOPS = {
    ast.Add: ast.Sub, ast.Sub: ast.Add, ast.Mult: ast.Div, ast.Div: ast.Mult,
    ast.FloorDiv: ast.Mult, ast.Mod: ast.FloorDiv, ast.Pow: ast.Mult,
    ast.BitAnd: ast.BitOr, ast.BitOr: ast.BitAnd, ast.BitXor: ast.BitOr,
    ast.LShift: ast.RShift, ast.RShift: ast.LShift,
}  # fmt: skip
_CMPOPS = {
    ast.Lt: ast.LtE, ast.LtE: ast.Lt, ast.Gt: ast.GtE, ast.GtE: ast.Gt,
    ast.Eq: ast.NotEq, ast.NotEq: ast.Eq, ast.Is: ast.IsNot, ast.IsNot: ast.Is,
    ast.In: ast.NotIn, ast.NotIn: ast.In,
}  # fmt: skip


def _skip(node, parents) -> bool:
    """Docstrings, ``__all__``, and anything inside a ``raise`` (its message)."""
    return any(isinstance(p, ast.Raise) for p in parents)


def sites(tree: ast.AST) -> list[tuple[str, tuple[int, ...]]]:
    """Every mutation site of ``tree`` as (kind, path of child indices), in a fixed order."""
    out = []

    def walk(node, path, parents):
        if _skip(node, parents):
            return
        if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
            out.append(("binop", path))
        elif isinstance(node, ast.Compare) and type(node.ops[0]) in _CMPOPS:
            out.append(("compare", path))
        elif isinstance(node, ast.BoolOp):
            out.append(("boolop", path))
        elif (
            isinstance(node, ast.Constant)
            and isinstance(node.value, (int, float))
            and not isinstance(node.value, bool)
        ):
            out.append(("constant", path))
        if isinstance(node, ast.stmt) and not isinstance(
            node, (ast.FunctionDef, ast.ClassDef, ast.Import, ast.ImportFrom, ast.Return)
        ):
            is_doc = isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant)
            targets = getattr(node, "targets", [])
            is_all = any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets)
            if not is_doc and not is_all and parents and not isinstance(node, ast.Raise):
                out.append(("delete", path))
        for i, child in enumerate(ast.iter_child_nodes(node)):
            walk(child, (*path, i), (*parents, node))

    walk(tree, (), ())
    return out


def _node_at(tree, path):
    node = tree
    for i in path:
        node = list(ast.iter_child_nodes(node))[i]
    return node


def _replace(tree, path, new):
    parent = _node_at(tree, path[:-1])
    target = list(ast.iter_child_nodes(parent))[path[-1]]
    for field, value in ast.iter_fields(parent):
        if value is target:
            setattr(parent, field, new)
            return
        if isinstance(value, list) and any(v is target for v in value):
            value[next(i for i, v in enumerate(value) if v is target)] = new
            return
    raise RuntimeError("site not found")


def mutate(tree: ast.AST, kind: str, path) -> tuple[ast.AST, str]:
    """A copy of ``tree`` with the mutation at ``path``, and its description."""
    tree = copy.deepcopy(tree)
    node = _node_at(tree, path)
    line = getattr(node, "lineno", "?")
    if kind == "binop":
        old = type(node.op)
        node.op = _BINOPS[old]()
        what = f"{old.__name__} -> {type(node.op).__name__}"
    elif kind == "compare":
        old = type(node.ops[0])
        node.ops[0] = _CMPOPS[old]()
        what = f"{old.__name__} -> {type(node.ops[0]).__name__}"
    elif kind == "boolop":
        old = type(node.op)
        node.op = ast.Or() if isinstance(node.op, ast.And) else ast.And()
        what = f"{old.__name__} -> {type(node.op).__name__}"
    elif kind == "constant":
        v = node.value
        node.value = 1 if v == 0 else (0 if v == 1 else v + 1)
        what = f"constant {v!r} -> {node.value!r}"
    else:
        _replace(tree, path, ast.Pass())
        what = f"delete {type(node).__name__}"
    return ast.fix_missing_locations(tree), f"line {line}: {what}"


def run_group(
    group: str, n: int, seed: int, timeout: float, only: set[int] | None = None
) -> tuple[int, int, list[str]]:
    """Mutants of ``group``: (killed, total, survivor descriptions); ``only``: the 1-based
    positions in the sample to run (the others are skipped and not counted)."""
    modules, tests = GROUPS[group]
    pool = []
    for rel in modules:
        tree = ast.parse((ROOT / "simlunar" / rel).read_text())
        pool += [(rel, tree, kind, path) for kind, path in sites(tree)]
    sample = random.Random(seed).sample(pool, min(n, len(pool)))
    killed, survivors = 0, []
    with tempfile.TemporaryDirectory(prefix="simlunar-mutants-") as tmp:
        pkg = Path(tmp) / "simlunar"
        shutil.copytree(ROOT / "simlunar", pkg, ignore=shutil.ignore_patterns("__pycache__"))
        env = {
            **os.environ,
            "PYTHONPATH": tmp + os.pathsep + str(ROOT),
            "NUMBA_CACHE_DIR": str(Path(tmp) / "numba"),
            "PYTHONDONTWRITEBYTECODE": "1",
        }
        cmd = [sys.executable, "-P", "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider", *tests]
        base = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
        if base.returncode != 0:  # a kill must be the mutant's doing
            raise SystemExit(f"{group}: the tests fail without a mutant:\n{base.stdout[-2000:]}")
        for i, (rel, tree, kind, path) in enumerate(sample):
            if only is not None and i + 1 not in only:
                continue
            mutant, what = mutate(tree, kind, path)
            target = pkg / rel
            original = target.read_text()
            target.write_text(ast.unparse(mutant))
            t0 = time.perf_counter()
            try:
                # -P: the working folder (the unmutated package) is not put on sys.path
                r = subprocess.run(
                    cmd, cwd=ROOT, env=env, capture_output=True, text=True, timeout=timeout
                )
                dead = r.returncode != 0
                how = "killed" if dead else "SURVIVED"
            except subprocess.TimeoutExpired:
                dead, how = True, "killed (timeout)"
            finally:
                target.write_text(original)
            killed += dead
            line = f"{group} {i + 1}/{len(sample)} {rel} {what}: {how}"
            print(f"{line} ({time.perf_counter() - t0:.1f} s)", flush=True)
            if not dead:
                survivors.append(f"{rel} {what}")
    return (
        killed,
        len(sample) if only is None else len(only & set(range(1, len(sample) + 1))),
        survivors,
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("groups", nargs="*", help=f"of {', '.join(GROUPS)}")
    ap.add_argument("--n", type=int, default=40, help="mutants per group (seeded sample)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--timeout", type=float, default=180.0, help="seconds per mutant's tests")
    ap.add_argument("--list", action="store_true", help="the groups and their sites")
    ap.add_argument(
        "--only", default=None, help="comma-separated positions in the sample (1-based) to run"
    )
    args = ap.parse_args(argv)
    if args.list:
        for g, (mods, tests) in GROUPS.items():
            count = sum(len(sites(ast.parse((ROOT / "simlunar" / m).read_text()))) for m in mods)
            print(f"{g}: {count} sites in {', '.join(mods)}; tests {', '.join(tests)}")
        return 0
    unknown = [g for g in args.groups if g not in GROUPS]
    if unknown or not args.groups:
        print(f"groups: {', '.join(GROUPS)}", file=sys.stderr)
        return 2
    for g in args.groups:
        only = None if args.only is None else {int(i) for i in args.only.split(",")}
        k, total, surv = run_group(g, args.n, args.seed, args.timeout, only)
        print(f"{g}: {k}/{total} killed ({100 * k / max(total, 1):.0f} %)", flush=True)
        for s in surv:
            print(f"  survivor: {s}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
