"""The import graph of the repository's packages, read from the source with ast (issue 35, item 5).

Every import statement counts, at module level and inside functions (a lazy import inside a function
is still an arrow between two modules), relative imports resolved against the importing module.
``from package import name`` is an arrow to ``package.name`` when that is a module, otherwise to
``package``. The arrows checked:

- no cycle among the modules of ``solver`` (each circle is reported, with one cycle through it);
- ``solver`` imports nothing from the packages built on it (``verification``, ``reference_cases``,
  ``scoursph``, ``benchmarks``, ``tests``);
- ``reference_cases`` (the reference runs of other codes) imports nothing from ``verification``
  (the cases that compare against them).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("solver", "scoursph", "verification", "reference_cases")
ABOVE_SOLVER = ("verification", "reference_cases", "scoursph", "benchmarks", "tests")


def module_files(root=ROOT, packages=PACKAGES):
    """{dotted module name: path} of every .py file of the packages (a package's __init__ is the package)."""
    modules = {}
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            parts = path.relative_to(root).with_suffix("").parts
            if parts[-1] == "__init__":
                parts = parts[:-1]
            modules[".".join(parts)] = path
    return modules


def imported_names(tree, module, is_package):
    """The dotted names a module's source imports, anywhere in it, relative imports resolved:
    (name, [imported attribute names]) for each ``from`` import, (name, []) for each ``import``."""
    package = module if is_package else module.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, []
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                name = ".".join(base + ([node.module] if node.module else []))
            else:
                name = node.module
            yield name, [alias.name for alias in node.names]


def import_graph(root=ROOT, packages=PACKAGES):
    """{module: {modules it imports}} over every dotted name imported (outside modules included as named)."""
    modules = module_files(root, packages)
    graph = {}
    for module, path in modules.items():
        tree = ast.parse(path.read_text(), filename=str(path))
        targets = set()
        for name, attributes in imported_names(tree, module, path.name == "__init__.py"):
            submodules = [f"{name}.{a}" for a in attributes if f"{name}.{a}" in modules]
            targets.update(submodules)
            if len(submodules) < len(attributes) or not attributes:
                targets.add(name)
        targets.discard(module)
        graph[module] = targets
    return graph


def find_cycle(graph, nodes):
    """One cycle among nodes (a list that starts and ends at the same module), or None."""
    state = {}  # 1: on the current path, 2: done
    path = []

    def visit(node):
        state[node] = 1
        path.append(node)
        for target in sorted(graph.get(node, ())):
            if target not in nodes:
                continue
            if state.get(target) == 1:
                return path[path.index(target) :] + [target]
            if target not in state:
                cycle = visit(target)
                if cycle:
                    return cycle
        path.pop()
        state[node] = 2
        return None

    for node in sorted(nodes):
        if node not in state:
            cycle = visit(node)
            if cycle:
                return cycle
    return None


def import_circles(graph, nodes):
    """The strongly connected sets of two or more nodes (each an import circle), sorted, as sorted lists."""
    index, low, on_stack, stack, circles = {}, {}, set(), [], []

    def connect(node):  # Tarjan's algorithm
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for target in sorted(graph.get(node, ())):
            if target not in nodes:
                continue
            if target not in index:
                connect(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    for node in sorted(nodes):
        if node not in index:
            connect(node)
    return sorted(circles)


def in_package(name, packages):
    return any(name == p or name.startswith(p + ".") for p in packages)


def arrows(graph, source_packages, target_packages):
    """The imports from modules of source_packages into target_packages, as 'a -> b' lines."""
    return sorted(
        f"{module} -> {target}"
        for module, targets in graph.items()
        if in_package(module, source_packages)
        for target in targets
        if in_package(target, target_packages)
    )


@pytest.fixture(scope="module")
def graph():
    return import_graph()


def test_the_graph_sees_lazy_and_relative_imports(graph):
    # solver/physics/__init__.py imports its terms relatively; the CLI imports the solver
    assert "solver.physics.gravity" in graph["solver.physics"]
    assert any(in_package(t, ("solver",)) for t in graph["scoursph.cli"])


def test_no_import_cycles_in_solver(graph):
    solver_modules = {m for m in graph if in_package(m, ("solver",))}
    circles = [" -> ".join(find_cycle(graph, set(c))) for c in import_circles(graph, solver_modules)]
    assert not circles, "import cycles in solver:\n" + "\n".join(circles)


def test_solver_imports_nothing_above_it(graph):
    back_up = arrows(graph, ("solver",), ABOVE_SOLVER)
    assert not back_up, "solver imports from the packages built on it:\n" + "\n".join(back_up)


def test_reference_cases_import_nothing_from_verification(graph):
    back_up = arrows(graph, ("reference_cases",), ("verification",))
    assert not back_up, "reference_cases imports from verification:\n" + "\n".join(back_up)


def test_find_cycle_reports_a_cycle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}
    assert find_cycle(graph, set(graph)) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}, {"a", "b"}) is None
    graph["e"] = {"f"}
    graph["f"] = {"e", "a"}
    assert import_circles(graph, set(graph)) == [["a", "b", "c"], ["e", "f"]]
