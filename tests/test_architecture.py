"""The package's layers, read from its source with ast: who may import whom.

core (the science) imports nothing of the package and reads no file. robot_models (robot
descriptions read from their URDF files) is the data layer: it imports nothing of the package
either. arms sits on both: it reads the shipped arms' URDFs, builds their plants and skills on
core's engine and promises them to core's SKILLS (the package root imports it, so every SKILLS a
program reaches holds them); every layer above core may use it. core <- study (the runner) <-
in_silico (simulated teachers) <- analysis, and core <- study <- classroom (a class's progress
files). Two edges sit on core side by side and never import each other: widgets (the notebook
views) and hardware (the uArm). apps (the pages and kiosks) is the top: it may use every layer,
and no layer imports it; cli (the command) sits beside it and reads study and class folders. No
import cycle, between modules or between subpackages; no import of a package module inside a function (the
way cycles get hidden); nothing below the widgets imports a widget library.
"""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = "mt_widgets"

#: Libraries that draw in a notebook or talk to a device: kept out of the science.
WIDGET_LIBRARIES = {"ipywidgets", "ipycanvas", "IPython", "traitlets", "anywidget", "ipyevents"}
CORE_FORBIDDEN = WIDGET_LIBRARIES | {"serial", "matplotlib"}


def module_name(path: Path, root: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def _resolve(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    """The absolute name a ``from ... import`` refers to, relative levels resolved."""
    if not node.level:
        return node.module or ""
    base = module.split(".")
    # In a package's __init__ one dot is the package itself; in a module, its parent.
    keep = len(base) - node.level + (1 if is_package else 0)
    anchor = base[:keep]
    return ".".join(anchor + ([node.module] if node.module else []))


def _in_type_checking(node, parents) -> bool:
    for parent in parents:
        if isinstance(parent, ast.If) and "TYPE_CHECKING" in ast.unparse(parent.test):
            return True
    return False


def read_imports(source: str, module: str, is_package: bool, modules: set[str], type_checking: bool = False):
    """[(imported module, line, inside a function)] of one module's source.

    ``from pkg import name`` counts as importing ``pkg.name`` when that is a module of the
    package, else ``pkg``. Imports under ``if TYPE_CHECKING:`` are not run and are skipped.
    """
    tree = ast.parse(source)
    found = []

    def visit(node, parents, in_function):
        for child in ast.iter_child_nodes(node):
            nested = in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
            if isinstance(child, ast.Import) and (type_checking or not _in_type_checking(child, parents)):
                found.extend((alias.name, child.lineno, in_function) for alias in child.names)
            elif isinstance(child, ast.ImportFrom) and (type_checking or not _in_type_checking(child, parents)):
                target = _resolve(module, is_package, child)
                if target == "__future__":
                    continue
                for alias in child.names:
                    candidate = f"{target}.{alias.name}"
                    found.append((candidate if candidate in modules else target, child.lineno, in_function))
            visit(child, parents + [child], nested)

    visit(tree, [], False)
    return found


def build_graph(root: Path, package: str = PACKAGE, type_checking: bool = False):
    """{module: [(imported module, line, inside a function)]} for every module under root/package;
    with ``type_checking``, the imports under ``if TYPE_CHECKING:`` too."""
    paths = sorted((root / package).rglob("*.py"))
    modules = {module_name(p, root): p for p in paths}
    names = set(modules)
    return {name: read_imports(path.read_text(encoding="utf-8"), name, path.name == "__init__.py", names, type_checking)
            for name, path in modules.items()}


def internal_edges(graph, package: str = PACKAGE) -> dict[str, set[str]]:
    return {m: {t for t, _, _ in imports if t == package or t.startswith(package + ".")} - {m}
            for m, imports in graph.items()}


def find_cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one member (Tarjan), each sorted."""
    index, low, on_stack, stack, order, cycles = {}, {}, set(), [], [0], []

    def connect(v):
        index[v] = low[v] = order[0]
        order[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in edges.get(v, ()):
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in sorted(edges):
        if v not in index:
            connect(v)
    return cycles


def layer(module: str) -> str:
    """The subpackage a module belongs to ("core", "study", ...), or "" for the package root."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


GRAPH = build_graph(ROOT)
EDGES = internal_edges(GRAPH)


def _imports_of(prefix: str):
    for module, imports in sorted(GRAPH.items()):
        if module == prefix or module.startswith(prefix + "."):
            for target, line, in_function in imports:
                yield module, target, line, in_function


# -- the checker itself ----------------------------------------------------------------------------

def test_the_checker_finds_a_cycle_and_a_function_level_import():
    assert find_cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert find_cycles({"a": {"b"}, "b": set()}) == []
    modules = {"p", "p.x", "p.y"}
    found = read_imports("from . import x\nfrom .y import f\ndef g():\n    from p import y\n", "p.z", False, modules)
    assert found == [("p.x", 1, False), ("p.y", 2, False), ("p.y", 4, True)]
    # In a package's __init__, "." is the package itself.
    assert read_imports("from .x import f\n", "p", True, modules) == [("p.x", 1, False)]
    assert read_imports("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import p.x\n", "p.y", False,
                        modules) == [("typing", 1, False)]
    assert read_imports("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import p.x\n", "p.y", False,
                        modules, type_checking=True) == [("typing", 1, False), ("p.x", 3, False)]


def test_the_graph_covers_every_layer():
    assert {layer(m) for m in GRAPH} >= {"", "core", "study", "in_silico", "analysis", "classroom", "widgets", "apps",
                                         "hardware"}
    assert "mt_widgets.core.skills" in EDGES["mt_widgets.core.episode_batch"]


# -- the rules -------------------------------------------------------------------------------------

def test_no_import_cycle_between_modules():
    assert find_cycles(EDGES) == []


def test_no_import_cycle_even_through_type_checking_imports():
    # Two modules that import each other only for annotations still depend on each other: a reader
    # cannot understand one without the other, and the first runtime use turns it into a real cycle.
    assert find_cycles(internal_edges(build_graph(ROOT, type_checking=True))) == []


def test_no_import_cycle_between_subpackages():
    packages: dict[str, set[str]] = {}
    for module, targets in EDGES.items():
        packages.setdefault(layer(module), set()).update(layer(t) for t in targets if layer(t) != layer(module))
    assert find_cycles(packages) == []


def test_no_package_module_is_imported_inside_a_function():
    hidden = [f"{m}:{line} imports {t}" for m, t, line, inside in _imports_of(PACKAGE)
              if inside and (t == PACKAGE or t.startswith(PACKAGE + "."))]
    assert hidden == []


def test_the_package_root_imports_only_core_and_the_arms():
    # The arms, so that the shipped arms' skills are in SKILLS whatever a program imports first.
    assert {layer(t) for t in EDGES[PACKAGE]} <= {"core", "arms"}


def test_core_imports_nothing_above_it_and_no_widget_serial_or_plotting_library():
    # Not even the robot models: reading a URDF is I/O, done above core (mt_widgets.arms).
    above = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of("mt_widgets.core")
             if t.startswith(PACKAGE) and layer(t) != "core"]
    libraries = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of("mt_widgets.core")
                 if t.split(".")[0] in CORE_FORBIDDEN]
    assert above == [] and libraries == []


def test_the_robot_models_import_nothing_of_the_package():
    # The URDF reader hands plain data up and knows nothing of plants or skills.
    found = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of("mt_widgets.robot_models")
             if t.startswith(PACKAGE + ".") and layer(t) != "robot_models"]
    assert found == []


def test_the_arms_import_only_core_and_the_robot_models():
    found = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of("mt_widgets.arms")
             if t.startswith(PACKAGE) and layer(t) not in ("core", "robot_models", "arms")]
    libraries = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of("mt_widgets.arms")
                 if t.split(".")[0] in CORE_FORBIDDEN]
    assert found == [] and libraries == []


def test_the_study_runner_imports_only_core_and_the_arms():
    # The package root counts as core and the arms: it imports nothing else (test above). A
    # protocol may name an arm (mt_widgets/study/protocol_arm.py), which the arms layer builds.
    wrong = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of("mt_widgets.study")
             if t.startswith(PACKAGE) and layer(t) not in ("core", "", "study", "arms", "robot_models")]
    libraries = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of("mt_widgets.study")
                 if t.split(".")[0] in CORE_FORBIDDEN]
    assert wrong == [] and libraries == []


@pytest.mark.parametrize("package, allowed", [
    ("in_silico", {"core", "", "study", "in_silico"}),
    ("analysis", {"core", "", "study", "in_silico", "analysis"}),
    ("classroom", {"core", "", "study", "classroom"}),
])
def test_the_simulation_and_the_analysis_sit_above_the_runner_without_widgets(package, allowed):
    prefix = f"{PACKAGE}.{package}"
    wrong = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of(prefix)
             if t.startswith(PACKAGE) and layer(t) not in allowed]
    libraries = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of(prefix)
                 if t.split(".")[0] in WIDGET_LIBRARIES]
    assert wrong == [] and libraries == []


@pytest.mark.parametrize("package", ["core", "study", "in_silico", "analysis", "classroom", "hardware"])
def test_nothing_below_the_widgets_imports_a_widget_library(package):
    libraries = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of(f"{PACKAGE}.{package}")
                 if t.split(".")[0] in WIDGET_LIBRARIES]
    assert libraries == []


@pytest.mark.parametrize("package, other", [("widgets", "hardware"), ("hardware", "widgets")])
def test_the_widgets_and_the_hardware_never_import_each_other(package, other):
    # Both are edges on core: a view draws any plant, the arm is driven by the apps that join them.
    wrong = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of(f"{PACKAGE}.{package}") if layer(t) == other]
    assert wrong == []


def test_the_widgets_and_the_hardware_import_only_core_and_the_arms():
    # The arms: the demo's arm chooser, the SO-101 connector's kinematics.
    for package in ("widgets", "hardware"):
        wrong = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of(f"{PACKAGE}.{package}")
                 if t.startswith(PACKAGE) and layer(t) not in ("core", "", "arms", package)]
        assert wrong == []


def test_the_apps_are_the_top_layer_nothing_else_imports():
    wrong = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of(PACKAGE)
             if layer(m) != "apps" and t.startswith(PACKAGE) and layer(t) == "apps"]
    assert wrong == []


def test_only_the_apps_import_the_classroom():
    wrong = [f"{m}:{line} imports {t}" for m, t, line, _ in _imports_of(PACKAGE)
             if layer(m) not in ("apps", "classroom", "cli") and t.startswith(PACKAGE) and layer(t) == "classroom"]
    assert wrong == []


def test_the_package_docstring_names_every_subpackage():
    import mt_widgets
    subpackages = {layer(m) for m in GRAPH} - {""}
    missing = [name for name in sorted(subpackages) if f"mt_widgets.{name}``" not in mt_widgets.__doc__]
    assert missing == []
