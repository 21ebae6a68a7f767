"""The house: jswim's import graph, function-level imports included, follows the layers
of docs/design.md, has no cycle, and every function-level import of a jswim module says why it is
lazy (a ``# lazy: ...`` comment: it keeps start-up light) or is on the list of today's debt.

Read from the source with ``ast`` (nothing is imported). An import of ``jswim`` itself (the
package root, e.g. for ``__version__``) is not an edge: every module's parent package is loaded
first anyway and it re-exports lazily.
"""

import ast
import functools
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "jswim"

#: docs/design.md's layers, bottom first; a module may import its own layer and those below.
#: The longest matching prefix decides.
LAYERS = [
    (
        "root",
        [
            "jswim.errors",
            "jswim.compile_cache",
            "jswim._io",
            "jswim._exports",
            "jswim.reprs",
        ],
    ),
    ("physics", ["jswim.swimmers"]),
    (
        "environment",
        [
            "jswim.env",
            "jswim.scenes",
            "jswim.integrate",
            "jswim.action_codes",
            "jswim.start_levels",
            "jswim.sharding",
        ],
    ),
    ("prompt text", ["jswim.prompt"]),
    ("LLM I/O", ["jswim.llm"]),
    (
        "judging",
        ["jswim.judging"],
    ),
    ("agents", ["jswim.agents"]),
    (
        "studies",
        [
            "jswim.studies",
            "jswim.figures",
            "jswim.results",
            "jswim.overview",
            "jswim.console",
        ],
    ),
    ("bench", ["jswim.bench"]),
    ("views", ["jswim.viz"]),
    ("front", ["jswim.cli", "jswim.__main__", "jswim.gym", "jswim.gymnax"]),
]

#: Upward imports that remain (the debt, documented): ``studies.run`` writes the report page at
#: the end of a study (docs/design.md: "the one call up a layer").
UPWARD_ALLOWED = {("jswim.studies.run", "jswim.viz.page")}

#: Import cycles that remain (none: plots <-> scene_plots went when the style moved to
#: jswim.figures.style; keep the list for a cycle that must be lived with, with its reason).
CYCLES_ALLOWED: list[set[str]] = []

#: Function-level imports of jswim modules without a ``# lazy:`` reason (the debt:
#: each either moves to the top of its module or gets its reason; the list only shrinks).
UNMARKED_ALLOWED: set[str] = set()  # the debt is paid: every function-level import says why


#: Imports of another module's underscore names that remain, in the agents, worlds and studies
#: layers (the debt: each helper becomes public in the module where it belongs, and its line goes;
#: the list only shrinks).
PRIVATE_IMPORTS_ALLOWED: set[str] = set()  # the debt is paid: shared helpers are public


def _modules() -> dict[str, Path]:
    out = {}
    for path in PACKAGE.rglob("*.py"):
        name = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        out[name.removesuffix(".__init__")] = path
    return out


@functools.cache
def _graph() -> tuple[tuple[str, str, bool, bool], ...]:
    """:func:`_imports` of jswim as it is on disk (read once per session)."""
    return tuple(_imports(_modules()))


def _imports(modules: dict[str, Path]) -> list[tuple[str, str, bool, bool]]:
    """``(importer, imported, inside a function, marked lazy)`` for every import of a jswim module."""

    def resolve(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    found = []
    for name, path in modules.items():
        text = path.read_text()
        lines = text.splitlines()
        is_pkg = path.name == "__init__.py"

        def visit(node: ast.AST, in_function: bool) -> None:
            for child in ast.iter_child_nodes(node):
                inside = in_function or isinstance(
                    child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)
                )
                if isinstance(child, (ast.Import, ast.ImportFrom)):
                    if isinstance(child, ast.Import):
                        targets = [a.name for a in child.names]
                    else:
                        base = child.module or ""
                        if child.level:
                            parts = name.split(".")[
                                : len(name.split(".")) - child.level + (1 if is_pkg else 0)
                            ]
                            base = ".".join(parts + ([base] if base else []))
                        targets = [f"{base}.{a.name}" for a in child.names]
                    marked = any(
                        "# lazy:" in ln for ln in lines[child.lineno - 1 : child.end_lineno]
                    )
                    for t in targets:
                        if t.split(".")[0] == "jswim":
                            r = resolve(t)
                            if r and r not in (name, "jswim"):
                                found.append((name, r, in_function, marked))
                visit(child, inside)

        visit(ast.parse(text), False)
    return found


def _layer(module: str) -> int:
    best = None
    for rank, (_, prefixes) in enumerate(LAYERS):
        for p in prefixes:
            if module == p or module.startswith(p + "."):
                if best is None or len(p) > best[1]:
                    best = (rank, len(p))
    assert best is not None, (
        f"{module} is in no layer of docs/design.md: add it to LAYERS (and the map)"
    )
    return best[0]


def _cycles(edges: dict[str, set[str]]) -> list[set[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]
    for root in list(edges):
        if root in index:
            continue
        work = [(root, iter(sorted(edges.get(root, ()))))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(edges.get(w, ())))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = set()
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.add(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(comp)
    return out


def test_every_module_sits_in_a_layer():
    for m in _modules():
        if m != "jswim":
            _layer(m)


def test_no_upward_import():
    imports = _graph()
    upward = sorted({(a, b) for a, b, _, _ in imports if _layer(b) > _layer(a)} - UPWARD_ALLOWED)
    assert not upward, "imports up a layer (docs/design.md, Layers): " + ", ".join(
        f"{a} -> {b}" for a, b in upward
    )


def test_no_import_cycle():
    edges = defaultdict(set)
    for a, b, _, _ in _graph():
        edges[a].add(b)
    cycles = [c for c in _cycles(edges) if c not in CYCLES_ALLOWED]
    assert not cycles, "import cycles (function-level imports included): " + "; ".join(
        " <-> ".join(sorted(c)) for c in cycles
    )


def test_function_level_imports_say_why():
    unmarked = {f"{a}->{b}" for a, b, inside, marked in _graph() if inside and not marked}
    new = sorted(unmarked - UNMARKED_ALLOWED)
    assert not new, (
        "imports inside functions with no reason: move them to the top of the module, or say "
        "why they must wait with a '# lazy: ...' comment (e.g. '# lazy: start-up'): "
        + ", ".join(new)
    )
    # The list of debt only shrinks: an entry that no longer occurs is removed from it.
    assert not (UNMARKED_ALLOWED - unmarked), sorted(UNMARKED_ALLOWED - unmarked)


def test_the_checker_sees_a_cycle_and_an_upward_import():
    # The checker itself: a made-up graph with a cycle, and a made-up upward edge.
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [{"a", "b", "c"}]
    assert _layer("jswim.agents.llm") > _layer("jswim.env.base") > _layer("jswim.swimmers.ng")


def _private_imports(modules: dict[str, Path]) -> set[str]:
    """``"importer -> home.name"`` for every import of another jswim module's underscore name."""
    found = set()
    for name, path in modules.items():
        is_pkg = path.name == "__init__.py"
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.ImportFrom):
                continue
            base = node.module or ""
            if node.level:
                parts = name.split(".")[: len(name.split(".")) - node.level + (1 if is_pkg else 0)]
                base = ".".join(parts + ([base] if base else []))
            if base.split(".")[0] != "jswim" or base == name:
                continue
            for alias in node.names:
                if alias.name.startswith("_") and not alias.name.startswith("__"):
                    found.add(f"{name} -> {base}.{alias.name}")
    return found


def test_no_module_imports_another_modules_private_names():
    """A helper that two modules share is public in the module where it belongs."""
    found = _private_imports(_modules())
    new = sorted(found - PRIVATE_IMPORTS_ALLOWED)
    assert not new, (
        "imports of another module's underscore names: make the helper public where it "
        "belongs (a name without the underscore, a docstring) and import that: " + ", ".join(new)
    )
    # The list of debt only shrinks: an entry that no longer occurs is removed from it.
    assert not (PRIVATE_IMPORTS_ALLOWED - found), sorted(PRIVATE_IMPORTS_ALLOWED - found)


def test_the_private_import_checker_sees_one(tmp_path):
    pkg = tmp_path / "jswim"
    pkg.mkdir()
    (pkg / "a.py").write_text("def _helper():\n    pass\n")
    (pkg / "b.py").write_text("from jswim.a import _helper\nfrom .a import __doc__\n")
    (pkg / "c.py").write_text("from . import a\nfrom .a import _helper as h\n")
    modules = {f"jswim.{p.stem}": p for p in pkg.glob("*.py")}
    assert _private_imports(modules) == {"jswim.b -> jswim.a._helper", "jswim.c -> jswim.a._helper"}
