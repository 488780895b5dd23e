"""The package's folders are the data flow, and no import climbs back up it.

Each top-level part of ``rattle_lab`` has a layer; a module may import only from its own part
or from parts of a lower layer.  The order (docs/dataflow.rst):

    model -> records, acoustics -> rig, store -> detect -> fit -> plot -> report
          -> workflow, exchange, explorer -> cli

``workflow`` sits after ``report`` because a pipeline's last stage renders the report from the
results the workflow computed; the report itself computes nothing and imports no workflow.

A second rule (issue 25, item 3): packages talk to each other through their public surfaces
only.  Every import that crosses from one package to another names something in the
target's ``__all__`` and takes it from the package itself, or from one of its public (no
``_``) modules, never from a private ``_module``.  A package is a public package (no part of
its dotted name starts with ``_``); its private subpackages (``records._readers``,
``model.sdf._kernel``, ...) and modules belong to it.  Imports inside one package, and from
a package's ancestors (``rattle_lab._atomic``, ``rattle_lab.exceptions``,
``rattle_lab.model.linear`` for ``rattle_lab.model.sdf``), may stay private: a subpackage
lies inside them.  Both checks read the sources with :mod:`ast` (nothing is imported), so
they see imports inside functions and under ``TYPE_CHECKING`` too.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "rattle_lab"

#: top-level part -> layer (lower = upstream).  Infrastructure modules are layer 0.
LAYER: dict[str, int] = {
    "__init__": 0, "__main__": 99, "_warmup": 99, "_version": 0, "exceptions": 0, "_atomic": 0,
    "_progress": 0, "_resources": 0, "_lazy": 0, "data": 0,
    "model": 1,
    "records": 2, "acoustics": 2,
    "rig": 3, "store": 3,
    "detect": 4,
    "fit": 5,
    "plot": 6,
    "report": 7,
    "workflow": 8, "exchange": 8, "explorer": 8,
    "cli": 9,
}


def _part(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def _imports(path: Path, root: Path = PACKAGE) -> list[tuple[int, str]]:
    rel = path.relative_to(root.parent).with_suffix("")
    name = ".".join(rel.parts)
    package = name if path.name == "__init__.py" else name.rsplit(".", 1)[0]
    if path.name == "__init__.py":
        name = name.removesuffix(".__init__")
        package = name
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names if a.name.startswith("rattle_lab")]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.startswith("rattle_lab"):
                if target == "rattle_lab":   # "from rattle_lab import x": x is the part
                    found += [(node.lineno, f"rattle_lab.{a.name}") for a in node.names]
                else:
                    found.append((node.lineno, target))
    return found


MODULES = sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


def test_every_part_has_a_layer():
    parts = {p.relative_to(PACKAGE).parts[0].removesuffix(".py") for p in MODULES}
    assert parts - set(LAYER) == set(), "give each new top-level part a layer"


def _violations(path: Path, root: Path = PACKAGE) -> list[str]:
    own = path.relative_to(root).parts[0].removesuffix(".py")
    bad = []
    for line, target in sorted(_imports(path, root)):
        other = _part(target)
        if other in LAYER and other != own and LAYER[other] > LAYER[own]:
            bad.append(f"line {line}: {target} ({other}, layer {LAYER[other]} > {LAYER[own]})")
    return bad


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_no_import_climbs_up_the_flow(path: Path):
    bad = _violations(path)
    assert not bad, f"{path.name} imports up the flow: " + "; ".join(bad)


def test_a_climbing_import_is_caught(tmp_path: Path):
    # the checker itself can fail: a store module that imports the fit (absolute, inside a
    # function) and the report (relative) is flagged twice; one that imports records is not
    probe = tmp_path / "rattle_lab" / "store" / "_probe.py"
    probe.parent.mkdir(parents=True)
    probe.write_text("from ..records import read\n"
                     "def f():\n    from rattle_lab.fit import fit_grazing\n"
                     "from ..report import write_report\n")
    bad = _violations(probe, tmp_path / "rattle_lab")
    assert [b.split(" (")[0] for b in bad] == ["line 3: rattle_lab.fit", "line 4: rattle_lab.report"]


# ----------------------------------------------------------------- public surfaces only


@dataclass(frozen=True)
class Module:
    source: str
    is_package: bool


@dataclass(frozen=True)
class Violation:
    importer: str
    line: int
    target: str
    name: str | None
    why: str

    def __str__(self) -> str:
        what = f"{self.target}.{self.name}" if self.name else self.target
        return f"{self.importer}:{self.line}: {what}: {self.why}"


def modules_on_disk(package_dir: Path = PACKAGE) -> dict[str, Module]:
    """Dotted module name -> source, for every ``.py`` file under ``package_dir``."""
    found = {}
    for path in sorted(package_dir.rglob("*.py")):
        parts = list(path.relative_to(package_dir.parent).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        if is_package:
            parts = parts[:-1]
        found[".".join(parts)] = Module(path.read_text(encoding="utf-8"), is_package)
    return found


def _private(dotted: str) -> bool:
    return any(part.startswith("_") for part in dotted.split(".") if part)


def _declared_all(source: str, where: str) -> list[str] | None:
    """The literal ``__all__`` of a module's source; None if it has none."""
    for node in ast.parse(source).body:
        targets = (node.targets if isinstance(node, ast.Assign)
                   else [node.target] if isinstance(node, ast.AnnAssign) else [])
        if any(isinstance(t, ast.Name) and t.id == "__all__" for t in targets):
            assert node.value is not None
            value = ast.literal_eval(node.value)  # a computed __all__ cannot be checked
            assert isinstance(value, (list, tuple)), where
            return list(value)
    return None


def _module_imports(name: str, module: Module) -> list[tuple[int, str, str | None, str | None]]:
    """``(line, target module, imported name, bound name)`` for every import of the module.

    The bound name is what the import defines in the module (None for ``import a.b``
    without ``as``).  Relative imports are resolved against ``name``.
    """
    out = []
    tree = ast.parse(module.source)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.extend((node.lineno, alias.name, None, alias.asname) for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = name.split(".") if module.is_package else name.split(".")[:-1]
                base = base[:len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            out.extend((node.lineno, target, alias.name, alias.asname or alias.name)
                       for alias in node.names)
    return out


def layer_violations(modules: dict[str, Module], root: str = "rattle_lab") -> list[Violation]:
    """Every cross-package import of ``modules`` that misses a public surface."""
    packages = {name for name, m in modules.items() if m.is_package}

    def owner(dotted: str) -> str:
        parts = dotted.split(".")
        for k in range(len(parts), 0, -1):
            candidate = ".".join(parts[:k])
            if candidate in packages and not _private(candidate):
                return candidate
        raise AssertionError(f"{dotted} is outside {root}")

    alls: dict[str, list[str] | None] = {}

    def public_names(dotted: str) -> list[str] | None:
        if dotted not in alls:
            alls[dotted] = _declared_all(modules[dotted].source, dotted)
        return alls[dotted]

    found = []
    for name, module in modules.items():
        home = owner(name)
        tree = ast.parse(module.source)
        for line, target, imported, bound in _module_imports(name, module):
            if target != root and not target.startswith(root + "."):
                continue
            if imported is not None and f"{target}.{imported}" in modules:
                target, imported = f"{target}.{imported}", None   # a module, imported by name
            if target not in modules:
                found.append(Violation(name, line, target, imported, "no such module"))
                continue
            there = owner(target)
            if there == home or home.startswith(there + "."):
                continue   # inside one package, or from a package that contains this one
            if _private(target[len(there):]):
                found.append(Violation(name, line, target, imported,
                                       f"private module of {there}; import from {there}"))
                continue
            declared = public_names(target)
            if declared is None:
                found.append(Violation(name, line, target, imported, "declares no __all__"))
            elif imported is not None and imported not in declared:
                found.append(Violation(name, line, target, imported,
                                       f"not in {target}.__all__"))
            elif imported is None and bound is not None:   # a module: the names used on it
                for node in ast.walk(tree):
                    if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                            and node.value.id == bound and node.attr not in declared):
                        found.append(Violation(name, node.lineno, target, node.attr,
                                               f"not in {target}.__all__"))
    return found


def test_no_import_reaches_past_a_public_surface():
    modules = modules_on_disk()
    assert len(modules) > 100   # the walk found the package
    found = layer_violations(modules)
    assert not found, "\n".join(map(str, found))


def test_the_check_finds_what_it_should():
    """A synthetic package tree with one import of every kind: the check flags the bad ones."""
    tree = {
        "pkg": Module("", True),
        "pkg._util": Module("X = 1\n", False),
        "pkg.low": Module('from ._impl import Thing, hidden\n__all__ = ["Thing"]\n', True),
        "pkg.low._impl": Module("Thing = 1\nhidden = 2\n", False),
        "pkg.low._sub": Module("", True),
        "pkg.low._sub.deep": Module("from pkg.low._impl import hidden\n", False),  # own package
        "pkg.low.open": Module('__all__ = ["f"]\ndef f(): pass\ndef g(): pass\n', False),
        "pkg.low.bare": Module("def h(): pass\n", False),
        "pkg.high": Module("", True),
        "pkg.high._mod": Module(
            "from pkg._util import X\n"              # 1 ancestor's private module: fine
            "from pkg.low import Thing\n"            # 2 fine
            "from pkg.low import hidden\n"           # 3 not in __all__
            "from pkg.low._impl import Thing\n"      # 4 private module
            "from pkg.low import _impl\n"            # 5 private module, by name
            "def late():\n"
            "    from ..low._sub import deep\n"      # 7 private subpackage, relative, in a function
            "from pkg.low.open import f, g\n"        # 8 g is not in open.__all__
            "import pkg.low.bare\n"                  # 9 a public module without __all__
            "import pkg.low\n"                       # 10 fine
            "from pkg.nowhere import y\n"            # 11 no such module
            "from pkg import low as lo\n"            # 12 a package as a module: fine ...
            "lo.Thing, lo.hidden\n",                 # 13 ... but hidden is not in its __all__
            False),
    }
    got = {(v.line, v.target, v.name) for v in layer_violations(tree, root="pkg")}
    assert got == {
        (3, "pkg.low", "hidden"),
        (4, "pkg.low._impl", "Thing"),
        (5, "pkg.low._impl", None),
        (7, "pkg.low._sub.deep", None),
        (8, "pkg.low.open", "g"),
        (9, "pkg.low.bare", None),
        (11, "pkg.nowhere", "y"),
        (13, "pkg.low", "hidden"),
    }


def _public_packages() -> list[str]:
    return sorted(name for name, m in modules_on_disk().items()
                  if m.is_package and not _private(name))


@pytest.mark.slow
def test_every_package_imports_first():
    """Each public package imports in a fresh state (no import cycle that only an order hides).

    Package ``__init__`` imports across packages can form cycles; each package is imported
    first, with every ``rattle_lab`` module dropped from ``sys.modules`` in between.
    """
    code = (
        "import importlib, sys\n"
        f"for name in {_public_packages()!r}:\n"
        "    for loaded in [m for m in sys.modules if m.split('.')[0] == 'rattle_lab']:\n"
        "        del sys.modules[loaded]\n"
        "    importlib.import_module(name)\n"
        "print('ok')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-3000:]
    assert out.stdout.strip() == "ok"


# ------------------------------------------------------------------- no hidden import circle
def _type_checking_only(tree: ast.AST) -> set[int]:
    """Lines of the imports under ``if TYPE_CHECKING:`` (they never run)."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and ast.unparse(node.test) in ("TYPE_CHECKING",
                                                                  "typing.TYPE_CHECKING"):
            found |= {n.lineno for stmt in node.body for n in ast.walk(stmt)
                      if isinstance(n, (ast.Import, ast.ImportFrom))}
    return found


def import_circles(modules: dict[str, Module], root: str = "rattle_lab") -> list[list[str]]:
    """The circles of the module import graph, imports inside functions included.

    An import inside a function that closes a circle still couples the modules both ways;
    only imports under ``TYPE_CHECKING`` are left out.  Returns each circle's modules
    (a strongly connected component with more than one module), sorted.
    """
    graph: dict[str, set[str]] = {name: set() for name in modules}
    for name, module in modules.items():
        skip = _type_checking_only(ast.parse(module.source))
        for line, target, imported, _bound in _module_imports(name, module):
            if line in skip or not (target == root or target.startswith(root + ".")):
                continue
            if imported is not None and f"{target}.{imported}" in modules:
                target = f"{target}.{imported}"
            if target in modules and target != name:
                graph[name].add(target)
    # Tarjan's strongly connected components, iteratively
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    circles = []
    for start in graph:
        if start in index:
            continue
        work = [(start, iter(sorted(graph[start])))]
        index[start] = low[start] = len(index)
        stack.append(start)
        on_stack.add(start)
        while work:
            v, children = work[-1]
            for w in children:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    component = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.append(w)
                        if w == v:
                            break
                    if len(component) > 1:
                        circles.append(sorted(component))
    return sorted(circles)


def test_no_import_circle():
    """No two modules import each other, directly or round a circle (issue 25, item 5)."""
    circles = import_circles(modules_on_disk())
    assert not circles, "import circles: " + "; ".join(" <-> ".join(c) for c in circles)


def test_the_circle_check_finds_a_hidden_circle():
    tree = {
        "pkg": Module("", True),
        # a -> b at import, b -> c in a function, c -> a in a function: one circle of three
        "pkg._a": Module("from ._b import f\n", False),
        "pkg._b": Module("def f():\n    from pkg._c import g\n", False),
        "pkg._c": Module("def g():\n    from . import _a\n", False),
        # d <-> e only for the type checker: no circle
        "pkg._d": Module("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n"
                         "    from ._e import E\n", False),
        "pkg._e": Module("from ._d import D\n", False),
    }
    assert import_circles(tree, root="pkg") == [["pkg._a", "pkg._b", "pkg._c"]]
