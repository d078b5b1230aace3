"""Imports run one way: the import-linter contracts of pyproject.toml hold (layers from the top,
no cycle between sibling modules, no Blender in bd_uv), no module of bd_uv is in an import
cycle (lazy imports included), and the linter does fail when a cycle comes back.
"""
import pathlib
import shutil
import subprocess
import sys

import grimp

REPO = pathlib.Path(__file__).resolve().parents[2]
LINT = ("import sys; from importlinter.cli import lint_imports; "
        "sys.exit(lint_imports(no_cache=True, no_logo=True))")


def lint_imports(root):
    """``lint-imports`` run in ``root`` (its pyproject.toml, its bd_uv): (exit code, output)."""
    proc = subprocess.run([sys.executable, "-c", LINT], cwd=root, capture_output=True,
                          text=True)
    return proc.returncode, proc.stdout + proc.stderr


def strongly_connected(edges):
    """The components with more than one node of a directed graph {node: set of nodes}
    (Tarjan, iterative)."""
    index, low, stack, on, out, counter = {}, {}, [], set(), [], [0]
    for root in edges:
        if root in index:
            continue
        work = [(root, iter(edges.get(root, ())))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            node, it = work[-1]
            for nxt in it:
                if nxt not in index:
                    index[nxt] = low[nxt] = counter[0]
                    counter[0] += 1
                    stack.append(nxt)
                    on.add(nxt)
                    work.append((nxt, iter(edges.get(nxt, ()))))
                    break
                if nxt in on:
                    low[node] = min(low[node], index[nxt])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    comp = []
                    while True:
                        w = stack.pop()
                        on.discard(w)
                        comp.append(w)
                        if w == node:
                            break
                    if len(comp) > 1:
                        out.append(sorted(comp))
    return out


def test_strongly_connected_finds_a_circle_and_nothing_else():
    edges = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": set(), "e": {"d"}}
    assert strongly_connected(edges) == [["a", "b", "c"]]


def test_the_contracts_hold():
    code, out = lint_imports(REPO)
    assert code == 0, out
    assert "3 kept, 0 broken" in out


def test_no_module_of_bd_uv_is_in_an_import_cycle():
    """Module by module, package __init__ files included, imports inside functions included."""
    sys.path.insert(0, str(REPO))
    try:
        graph = grimp.build_graph("bd_uv", cache_dir=None)
    finally:
        sys.path.remove(str(REPO))
    edges = {m: {i for i in graph.find_modules_directly_imported_by(m) if i.startswith("bd_uv")}
             for m in graph.modules}
    assert len(edges) > 50
    assert strongly_connected(edges) == []


def test_a_lazy_import_back_up_breaks_the_contracts(tmp_path):
    """The linter sees an import inside a function: the seam search's own cycle, put back."""
    shutil.copytree(REPO / "bd_uv", tmp_path / "bd_uv",
                    ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(REPO / "pyproject.toml", tmp_path)
    assert lint_imports(tmp_path)[0] == 0
    with open(tmp_path / "bd_uv" / "unwrapping" / "unwrap.py", "a", encoding="utf-8") as fh:
        fh.write("\n\ndef _auto():\n    from ..seams import unwrap_auto\n    return unwrap_auto\n")
    code, out = lint_imports(tmp_path)
    assert code == 1
    assert "bd_uv.unwrapping is not allowed to import bd_uv.seams" in out
    assert "2 broken" in out
