"""The house: jswim's import graph, function-level imports included, follows the layers
of docs/design.md (data flows one way: physics -> runs -> the folder -> pictures), has no cycle
between modules nor between packages, and every function-level import of a jswim module says why
it is lazy (a ``# lazy: ...`` comment: it keeps start-up light) or is on the list of today's debt.

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
            "jswim.reals",
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
    # plan, run, write the folder; read it back (tables, show, compare): a study ends at its folder
    ("studies", ["jswim.studies", "jswim.results", "jswim.console"]),
    ("bench", ["jswim.bench"]),  # runs suites of studies, computes the leaderboard from folders
    ("pictures", ["jswim.figures", "jswim.viz"]),  # read folders, draw (jswim.viz.publish)
    ("front", ["jswim.cli", "jswim.__main__", "jswim.gym", "jswim.gymnax"]),
]

#: Upward imports that remain (none: the study no longer draws; jswim.viz.publish does, after it).
UPWARD_ALLOWED: set[tuple[str, str]] = set()

#: Cycles between packages (``jswim.env`` <-> ``jswim.scenes`` counts even when no two modules
#: form a cycle) that remain, each with its reason (none: scene physics sits below the worlds).
PACKAGE_CYCLES_ALLOWED: list[set[str]] = []

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
    if module == "jswim":
        return len(LAYERS) - 1  # jswim/__init__.py is in the front layer (a prefix would hold all)
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


def _package(module: str) -> str:
    """The package a module belongs to: ``jswim.env.registry`` -> ``jswim.env``; a root module
    (``jswim.gym``) is its own."""
    return ".".join(module.split(".")[:2])


def _package_edges(imports) -> dict[str, set[str]]:
    """Package -> the packages it imports, function-level imports included (the root ``jswim``
    is no edge: see the module docstring)."""
    edges: dict[str, set[str]] = defaultdict(set)
    for a, b, _, _ in imports:
        pa, pb = _package(a), _package(b)
        if pa != pb and "jswim" not in (pa, pb):
            edges[pa].add(pb)
    return edges


def test_no_package_cycle():
    """One way down between packages too: studies never reach the pictures, lazily or not."""
    cycles = [c for c in _cycles(_package_edges(_graph())) if c not in PACKAGE_CYCLES_ALLOWED]
    assert not cycles, (
        "package-level import cycles (function-level imports included): "
        + "; ".join(" <-> ".join(sorted(c)) for c in cycles)
    )


def test_studies_import_nothing_that_draws():
    """A study ends at its folder: nothing under jswim/studies/ (nor bench, nor results) imports
    jswim.figures or jswim.viz, at the top or inside a function."""
    drawing = sorted(
        f"{a} -> {b}"
        for a, b, _, _ in _graph()
        if _package(a) in ("jswim.studies", "jswim.results", "jswim.bench", "jswim.console")
        and _package(b) in ("jswim.figures", "jswim.viz")
    )
    assert not drawing, drawing


def test_the_package_checker_sees_a_cycle_made_of_function_level_imports(tmp_path):
    # Two packages whose modules form no module-level cycle, tied both ways by imports inside
    # functions: the package graph has the cycle, and the checker reads those imports.
    root = tmp_path / "jswim"
    for pkg in ("a", "b"):
        (root / pkg).mkdir(parents=True)
        (root / pkg / "__init__.py").write_text("")
    (root / "a" / "x.py").write_text("def f():\n    from jswim.b import y  # lazy: test\n")
    (root / "b" / "y.py").write_text("")
    (root / "b" / "z.py").write_text("def g():\n    import jswim.a.w\n")
    (root / "a" / "w.py").write_text("")
    (root / "c.py").write_text("from jswim.a import x\n")
    modules = {
        ".".join(p.relative_to(tmp_path).with_suffix("").parts).removesuffix(".__init__"): p
        for p in root.rglob("*.py")
    }
    imports = _imports(modules)
    assert {(a, b, inside) for a, b, inside, _ in imports} == {
        ("jswim.a.x", "jswim.b.y", True),
        ("jswim.b.z", "jswim.a.w", True),
        ("jswim.c", "jswim.a.x", False),
    }
    module_edges = defaultdict(set)
    for a, b, _, _ in imports:
        module_edges[a].add(b)
    assert _cycles(module_edges) == []  # no two modules import each other
    edges = _package_edges(imports)
    assert edges == {"jswim.a": {"jswim.b"}, "jswim.b": {"jswim.a"}, "jswim.c": {"jswim.a"}}
    assert _cycles(edges) == [{"jswim.a", "jswim.b"}]
    assert _package("jswim.gym") == "jswim.gym" and _package("jswim.viz.page") == "jswim.viz"


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
    # the flow: studies (and results) below the bench, both below the pictures
    assert _layer("jswim.viz.page") == _layer("jswim.figures.plots") > _layer("jswim.bench.runner")
    assert _layer("jswim.bench.runner") > _layer("jswim.studies.run") == _layer("jswim.results")


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


def _private_module_reads(modules: dict[str, Path]) -> set[str]:
    """``"reader -> module._name"`` for every read of an underscore attribute of a jswim module
    the reader imported by name (``from jswim.bench import runner; runner._helper(...)``)."""
    found = set()
    for name, path in modules.items():
        tree = ast.parse(path.read_text())
        bound: dict[str, str] = {}
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.name.startswith("jswim.") and a.name in modules:
                        bound[a.asname or a.name] = a.name
            elif isinstance(node, ast.ImportFrom) and (node.module or "").startswith("jswim"):
                for a in node.names:
                    full = f"{node.module}.{a.name}"
                    if full in modules:
                        bound[a.asname or a.name] = full
        for node in ast.walk(tree):
            if (
                isinstance(node, ast.Attribute)
                and isinstance(node.value, ast.Name)
                and node.value.id in bound
                and node.attr.startswith("_")
                and not node.attr.startswith("__")
            ):
                found.add(f"{name} -> {bound[node.value.id]}.{node.attr}")
    return found


def test_no_module_reads_another_modules_private_attributes():
    found = sorted(_private_module_reads(_modules()))
    assert not found, "reads of another module's underscore names: " + ", ".join(found)


def test_the_private_read_checker_sees_one(tmp_path):
    pkg = tmp_path / "jswim"
    pkg.mkdir()
    (pkg / "a.py").write_text("def _helper():\n    pass\n")
    (pkg / "b.py").write_text("from jswim import a\na._helper()\na.__name__\n")
    modules = {f"jswim.{p.stem}": p for p in pkg.glob("*.py")}
    assert _private_module_reads(modules) == {"jswim.b -> jswim.a._helper"}
