"""The package's import graph, read from the source: no cycle, no private name used across
modules, every name imported from the module that defines it."""
from __future__ import annotations

import ast
import re
from functools import lru_cache
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[2] / "ddp_lite"
HANDLER = re.compile(r"ddp_lite(\.\w+)+:\w+")


def module_name(path: Path) -> str:
    """``ddp_lite/a/b.py`` → ``ddp_lite.a.b``; ``ddp_lite/a/__init__.py`` → ``ddp_lite.a``."""
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


@lru_cache(maxsize=None)
def _package_files() -> tuple[Path, ...]:
    return tuple(sorted(PACKAGE.rglob("*.py")))


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in _package_files()}


@lru_cache(maxsize=None)
def _parsed(source: str) -> ast.Module:
    """``source`` parsed once per session: the checks below read the same files and cells again and again
    (the trees are only read, never changed)."""
    return ast.parse(source)


def _parsed_file(path: Path) -> ast.Module:
    return _parsed(path.read_text(encoding="utf-8"))


@lru_cache(maxsize=None)
def _nodes(source: str) -> tuple[ast.AST, ...]:
    """Every node of ``source``'s tree in ``ast.walk`` order, listed once per session: the checks below go
    over every node of every file, several times each."""
    return tuple(ast.walk(_parsed(source)))


def _file_nodes(path: Path) -> tuple[ast.AST, ...]:
    return _nodes(path.read_text(encoding="utf-8"))


def resolve(importer: str, is_package: bool, level: int, target: str | None) -> str:
    """The absolute name of ``from <level dots><target> import ...`` written in ``importer``."""
    if level == 0:
        return target or ""
    base = importer.split(".")
    base = base if is_package else base[:-1]
    base = base[: len(base) - (level - 1)]
    return ".".join(base + ([target] if target else []))


def imports(name: str, path: Path, known: dict[str, Path]):
    """(imported module, names taken from it) for every import of a package module in ``path``,
    at any depth (imports inside functions count too), and every ``"ddp_lite.module:name"`` string
    (a handler the command line imports by name)."""
    is_package = path.name == "__init__.py"
    for node in _file_nodes(path):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and HANDLER.fullmatch(node.value):
            module, taken = node.value.split(":")
            if module in known:
                yield module, (taken,)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name in known:
                    yield alias.name, ()
        elif isinstance(node, ast.ImportFrom):
            source = resolve(name, is_package, node.level, node.module)
            if source not in known:
                continue
            taken = []
            for alias in node.names:
                if f"{source}.{alias.name}" in known:  # ``from . import losses``: a module, not a name
                    yield f"{source}.{alias.name}", ()
                else:
                    taken.append(alias.name)
            if taken:
                yield source, tuple(taken)


@lru_cache(maxsize=None)
def graph() -> dict[str, dict[str, set[str]]]:
    """importer → {imported module → names taken} over the package (a package's ``__init__``,
    which only hands names on lazily, is left out as an importer). Built once per session: the checks
    only read it."""
    known = modules()
    edges: dict[str, dict[str, set[str]]] = {}
    for name, path in known.items():
        out = edges.setdefault(name, {})
        for target, names in imports(name, path, known):
            if target != name and target != "ddp_lite":
                out.setdefault(target, set()).update(names)
    return edges


def cycles(edges: dict[str, dict[str, set[str]]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in edges.get(v, {}):
            if w not in index:
                visit(w)
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
                found.append(sorted(component))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return found


def defined_names(path: Path) -> set[str]:
    """Names a module defines at its top level (functions, classes, assignments), not those it imports."""
    names = set()
    for node in _parsed_file(path).body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            for target in node.targets if isinstance(node, ast.Assign) else [node.target]:
                names.update(n.id for n in ast.walk(target) if isinstance(n, ast.Name))
    return names


def test_the_package_has_no_import_cycle():
    assert cycles(graph()) == []


def test_no_private_name_is_imported_from_another_module():
    crossing = [f"{importer} takes {name} from {source}" for importer, out in graph().items()
                for source, names in out.items() for name in names if name.startswith("_")]
    assert crossing == []


def test_every_name_is_imported_from_the_module_that_defines_it():
    known = modules()
    defined = {name: defined_names(path) for name, path in known.items()}
    second_hand = [f"{importer} takes {name} from {source}" for importer, out in graph().items()
                   for source, names in out.items() for name in names
                   if not source.endswith("ddp_lite") and name not in defined[source]]
    assert second_hand == []


def test_the_checks_see_what_they_must():
    # a cycle through an import inside a function, and a relative import one level up, are found
    edges = {"p.a": {"p.b": set()}, "p.b": {"p.c": set()}, "p.c": {"p.a": set()}, "p.d": {"p.a": set()}}
    assert cycles(edges) == [["p.a", "p.b", "p.c"]]
    assert resolve("ddp_lite.x.y", False, 2, "z") == "ddp_lite.z"
    assert resolve("ddp_lite.x", True, 1, "y") == "ddp_lite.x.y"
    late = ast.parse("def f():\n    from .fit import complete_depth\n")
    assert any(isinstance(n, ast.ImportFrom) and n.module == "fit" for n in ast.walk(late))
    assert HANDLER.fullmatch("ddp_lite.interface.cli_demo:demo_command") and not HANDLER.fullmatch("ddp_lite.interface.cli_demo")


def allowed_imports(package: Path) -> set[str] | None:
    """The sub-packages ``package``'s docstring says it may import ("May import: a, b." / "Imports no
    other part" / "every other part"); None: every one."""
    doc = ast.get_docstring(ast.parse((package / "__init__.py").read_text(encoding="utf-8"))) or ""
    if "every other part" in doc:
        return None
    if "Imports no other part" in doc:
        return set()
    found = re.search(r"May import: ([\w, ]+)\.", doc)
    assert found, f"{package.name}/__init__.py must say what it may import"
    return {name.strip() for name in found.group(1).split(",")}


def test_each_sub_package_imports_only_what_its_docstring_allows():
    packages = sorted(p.parent for p in PACKAGE.glob("*/__init__.py"))
    assert packages, "ddp_lite has sub-packages"
    breaches = []
    for importer, out in graph().items():
        parts = importer.split(".")
        if len(parts) < 3:
            continue
        allowed = allowed_imports(PACKAGE / parts[1])
        for target in out:
            other = target.split(".")
            if len(other) >= 2 and other[1] != parts[1] and allowed is not None and other[1] not in allowed:
                breaches.append(f"{importer} imports {target}")
    assert breaches == []


def part_of_method(name: str) -> str | None:
    """The part of ``ddp_lite.method`` a module belongs to: its sub-package (``paper``, ``kit``, ``runtime``),
    ``"method"`` for the fit's own files in ``method/``, None outside ``method``."""
    parts = name.split(".")
    if parts[:2] != ["ddp_lite", "method"] or len(parts) < 3:
        return None
    return parts[2] if (PACKAGE / "method" / parts[2] / "__init__.py").exists() else "method"


def test_each_part_of_the_method_imports_only_what_its_docstring_allows():
    """Inside ``method`` the same rule one level down: ``paper`` imports none of the rest of ``method``
    (and so nothing of the kit), the kit and the runtime what their docstrings name (``method``: the
    fit's files in ``method/`` itself); outside ``method`` too, each only the parts it names."""
    subs = {p.parent.name for p in (PACKAGE / "method").glob("*/__init__.py")}
    assert subs >= {"paper", "kit", "runtime"}
    breaches = []
    for importer, out in graph().items():
        part = part_of_method(importer)
        if part in (None, "method") or importer.endswith(f".{part}"):
            continue
        allowed = allowed_imports(PACKAGE / "method" / part)
        for target in out:
            other = part_of_method(target) or target.split(".")[1]
            if other != part and allowed is not None and other not in allowed:
                breaches.append(f"{importer} imports {target}")
    assert breaches == []


BELOW_THE_KIT = {"ddp_lite.method.stopping", "ddp_lite.method.result"}  # the fit's files the kit may use


def test_the_methods_rooms_import_only_downward():
    """paper below runtime below kit below the fit's own files: the paper imports none of the rest, the
    runtime only the paper, the kit of ``method/`` itself only the held-out pixels (``stopping``) and the
    result type (``result``), which import nothing of the kit and nothing of the fit above them."""
    edges = graph()
    up = {"paper": {"runtime", "kit", "method"}, "runtime": {"kit", "method"}, "kit": {"method"}}
    breaches = [f"{importer} imports {target}" for importer, out in edges.items() for target in out
                if part_of_method(importer) in up and part_of_method(target) in up[part_of_method(importer)]
                and target not in BELOW_THE_KIT]
    assert breaches == []
    below_kit = set().union(*(edges[module] for module in BELOW_THE_KIT))
    assert all(part_of_method(module) in ("paper", "runtime", None) for module in below_kit)


def _ddp_lite_imports(source: str, importer: str | None = None, is_package: bool = False):
    """(line, absolute module name) of every import of ``ddp_lite`` or one of its modules in ``source``."""
    for node in _nodes(source):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "ddp_lite":
                    yield node.lineno, alias.name
        elif isinstance(node, ast.ImportFrom):
            if node.level and importer is None:
                continue  # a relative import outside the package: not ours
            target = resolve(importer, is_package, node.level, node.module) if node.level else node.module or ""
            if target.split(".")[0] == "ddp_lite":
                yield node.lineno, target


def _outside_sources():
    """(where, source) of every file outside the package that imports it: tests, benchmarks, the downloader,
    and each notebook's code cells (magics left out)."""
    import json
    root = PACKAGE.parent
    for folder in ("tests", "benchmarks", "data_fetch"):
        # the tests sit in folders laid out like the package (tests/method/kit/...): all of them
        for path in sorted((root / folder).rglob("*.py") if folder == "tests" else (root / folder).glob("*.py")):
            yield str(path.relative_to(root)), path.read_text(encoding="utf-8")
    for path in sorted((root / "notebooks").glob("*.ipynb")):
        for i, cell in enumerate(json.loads(path.read_text(encoding="utf-8"))["cells"]):
            if cell["cell_type"] == "code":
                source = "".join(cell["source"])
                source = "\n".join(l for l in source.splitlines() if not l.lstrip().startswith(("%", "!")))
                yield f"{path.relative_to(root)} cell {i}", source


def _names_taken(source: str):
    """(line, module, name) of every ``from ddp_lite... import name`` in ``source`` (a module taken as a
    name is left out), and (line, "ddp_lite", name) of every ``ddp.name`` after ``import ddp_lite as ddp``."""
    known = modules()
    aliases = set()
    for node in _nodes(source):
        if isinstance(node, ast.ImportFrom) and not node.level and (node.module or "").split(".")[0] == "ddp_lite":
            for alias in node.names:
                if f"{node.module}.{alias.name}" not in known:
                    yield node.lineno, node.module, alias.name
        elif isinstance(node, ast.Import):
            aliases |= {alias.asname or alias.name for alias in node.names if alias.name == "ddp_lite"}
    for node in _nodes(source):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in aliases:
            yield node.lineno, "ddp_lite", node.attr


def test_every_import_of_the_package_names_a_module_that_exists():
    """Also the late imports inside functions, and those of tests, benchmarks and notebooks, which no other
    test may reach (a module moved into a sub-package leaves them pointing at nothing)."""
    known = set(modules())
    root = PACKAGE.parent
    missing = []
    for name, path in modules().items():
        for line, target in _ddp_lite_imports(path.read_text(encoding="utf-8"), name, path.name == "__init__.py"):
            if target not in known:
                missing.append(f"{path.relative_to(root)}:{line}: {target}")
    for where, source in _outside_sources():
        for line, target in _ddp_lite_imports(source):
            if target not in known:
                missing.append(f"{where}:{line}: {target}")
    assert not missing, "imports of modules that do not exist:\n" + "\n".join(missing)


def test_tests_benchmarks_and_notebooks_take_each_name_from_the_module_that_defines_it():
    """The rules outside the package: every name comes from its own module, never through the package's
    front door or another module; a notebook, which students read as the way to use the kit, takes no
    private name."""
    defined = {name: defined_names(path) for name, path in modules().items()}
    second_hand, private = [], []
    for where, source in _outside_sources():
        for line, module, name in _names_taken(source):
            if name not in defined[module]:  # the front door's own names (__all__) aside, none through it
                second_hand.append(f"{where}:{line}: {name} from {module}")
            if name.startswith("_") and where.startswith("notebooks"):
                private.append(f"{where}:{line}: {name} from {module}")
    assert second_hand == [] and private == []


def test_no_module_hands_on_a_name_it_does_not_define():
    """A module's ``__all__`` names what it defines: no name lives on at an old address. The package's
    front door names each name's own module, and that module defines it."""
    import ddp_lite
    handed_on = []
    for name, path in modules().items():
        if name == "ddp_lite":
            continue
        for node in _parsed_file(path).body:
            if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
                handed_on += [f"{name}: {n}" for n in ast.literal_eval(node.value) if n not in defined_names(path)]
    assert handed_on == []
    assert ddp_lite.__all__ == list(ddp_lite._FRONT_DOOR)
    assert all(name in defined_names(modules()[f"ddp_lite.{module}"]) for name, module in ddp_lite._FRONT_DOOR.items())


def test_each_sub_package_names_its_modules_in_its_docstring():
    """The one list of the package's modules: each sub-package's docstring names each of its modules
    (``name``) and sub-packages, and the package's docstring each sub-package."""
    unnamed = []
    for init in sorted(PACKAGE.rglob("__init__.py")):
        doc = ast.get_docstring(ast.parse(init.read_text(encoding="utf-8"))) or ""
        parts = [p.stem for p in init.parent.glob("*.py") if p.name != "__init__.py"]
        parts += [p.parent.name for p in init.parent.glob("*/__init__.py")]
        unnamed += [f"{init.parent.relative_to(PACKAGE.parent)}: {part}" for part in sorted(parts)
                    if not re.search(rf"``{part}(\.py|/)?``", doc)]
    assert unnamed == []


def test_the_fit_does_not_import_its_combiner():
    # one fit is a straight path: the combiner (blend, fill, ensemble) calls it, never the reverse
    edges = graph()
    assert "ddp_lite.method.fit" in edges["ddp_lite.method.complete"]
    assert "ddp_lite.method.complete" not in edges["ddp_lite.method.fit"]
    assert not {"ddp_lite.method.kit.blend", "ddp_lite.method.kit.ensemble", "ddp_lite.method.kit.combine"} \
        & set(edges["ddp_lite.method.fit"])


def test_the_package_never_imports_the_downloader():
    """``data_fetch`` may use ``ddp_lite.core`` (its file helpers), never the reverse: the kit reads files
    the downloader left on disk and needs none of its code (no loader fetches)."""
    root = PACKAGE.parent
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in _file_nodes(path):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) and node.level == 0 else []
            found += [f"{path.relative_to(root)}:{node.lineno}: {n}" for n in names if n.split(".")[0] == "data_fetch"]
    assert found == []
