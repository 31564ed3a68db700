"""The package's shape (docs/contributing/layout.md), read off the source with an AST walk over `verify/`:
no import cycle between modules (imports inside functions count: a lazy import is still a dependency),
no private name (`_x`) imported from another module, the leaves and the model importing no layer above
them, at most 20 `# type: ignore` (each with its reason on the line) and no module over 800 lines."""
from __future__ import annotations

import ast
import re
from dataclasses import dataclass
from pathlib import Path

import networkx as nx

ROOT = Path(__file__).resolve().parent.parent
PACKAGE = ROOT / "verify"
MAX_IGNORES = 20
MAX_LINES = 800
#: what each lower layer may import from verify (itself included)
ALLOWED = {"verify.core": ("verify.core",),
           "verify.model": ("verify.core", "verify.model")}


@dataclass(frozen=True)
class Import:
    importer: str    # the importing module
    module: str      # the module imported from (or imported)
    name: str        # the name imported ("" for `import x`)
    line: int


def modules() -> dict[str, Path]:
    found = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        if "ros1_runtime" in path.parts:  # files the generated nodes run, not part of the package's code
            continue
        parts = list(path.relative_to(ROOT).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        found[".".join(parts)] = path
    return found


MODULES = modules()


def imports_of(name: str, path: Path) -> list[Import]:
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[:len(package.split(".")) - node.level + 1]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            found += [Import(name, module, alias.name, node.lineno) for alias in node.names]
        elif isinstance(node, ast.Import):
            found += [Import(name, alias.name, "", node.lineno) for alias in node.names]
    return [i for i in found if i.module == "verify" or i.module.startswith("verify.")]


IMPORTS = [i for name, path in MODULES.items() for i in imports_of(name, path)]


def target(i: Import) -> str:
    """The module an import depends on: a submodule imported by name, else the module imported from."""
    sub = f"{i.module}.{i.name}"
    return sub if sub in MODULES else i.module


def test_no_import_cycle():
    graph = nx.DiGraph()
    graph.add_edges_from((i.importer, target(i)) for i in IMPORTS if target(i) != i.importer)
    cycles = sorted(sorted(c) for c in nx.simple_cycles(graph))
    assert cycles == [], "\n".join(" -> ".join(c) for c in cycles)


def test_no_private_name_is_imported_from_another_module():
    private = [f"{MODULES[i.importer].relative_to(ROOT)}:{i.line}: {i.name} from {i.module}" for i in IMPORTS
               if i.name.startswith("_") and not i.name.startswith("__")]
    assert private == []


def test_the_leaves_and_the_model_import_no_layer_above_them():
    upward = [f"{MODULES[i.importer].relative_to(ROOT)}:{i.line}: {target(i)}" for i in IMPORTS
              for layer, allowed in ALLOWED.items()
              if (i.importer == layer or i.importer.startswith(layer + "."))
              and not any(target(i) == a or target(i).startswith(a + ".") for a in allowed)]
    assert upward == []


IGNORE = re.compile(r"#\s*type:\s*ignore(\[[^\]]*\])?(.*)$")


def test_few_type_ignores_each_with_its_reason():
    ignores = [(path, n, m) for path in MODULES.values()
               for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
               if (m := IGNORE.search(line))]
    unexplained = [f"{p.relative_to(ROOT)}:{n}" for p, n, m in ignores
                   if not m.group(1) or not re.search(r"[A-Za-z]{3}", m.group(2))]
    assert unexplained == [], "an ignore names its error code and says why on the same line"
    assert len(ignores) <= MAX_IGNORES, [f"{p.relative_to(ROOT)}:{n}" for p, n, _ in ignores]


def test_no_module_is_over_800_lines():
    long = {str(p.relative_to(ROOT)): n for p in MODULES.values()
            if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_LINES}
    assert long == {}


def test_the_top_level_keeps_only_the_api_the_cli_and_the_entry_points():
    top = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert top == ["__init__.py", "__main__.py", "api.py", "cli.py"]


def test_the_walk_sees_the_package():
    """The checks above are not vacuous: the walk finds the package's modules and their imports."""
    assert {"verify.api", "verify.core.source", "verify.timing.rta", "verify.frontend.parse"} <= set(MODULES)
    assert any(i.importer == "verify.api" and target(i).startswith("verify.frontend") for i in IMPORTS)
