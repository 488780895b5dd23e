"""The package's folders are the data flow, and no import climbs back up it.

Each top-level part of ``rattle_lab`` has a layer; a module may import only from its own part
or from parts of a lower layer.  The order (docs/dataflow.rst):

    model -> records, acoustics -> rig, store -> detect -> fit -> plot -> report
          -> workflow, exchange, explorer -> cli

``workflow`` sits after ``report`` because a pipeline's last stage renders the report from the
results the workflow computed; the report itself computes nothing and imports no workflow.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "rattle_lab"

#: top-level part -> layer (lower = upstream).  Infrastructure modules are layer 0.
LAYER: dict[str, int] = {
    "__init__": 0, "__main__": 99, "_version": 0, "exceptions": 0, "_atomic": 0,
    "_progress": 0, "_resources": 0, "data": 0,
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
