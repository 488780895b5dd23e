"""Build hook: ship the top-level resource folders inside the package.

All metadata lives in pyproject.toml.  This file only extends ``build_py`` so that a wheel
(``pip install .``) carries the scenes (``synthetic/*.toml``), the pipelines
(``pipelines/*.toml``), the mappings (``data_schema/mappings/*.toml``) and the record
schema (``data_schema/*.json``) as ``rattle_lab/data/<kind>/``, where
:mod:`rattle_lab._resources` finds them by name.  The list is that module's
(``RESOURCE_KINDS``, ``checkout_files``), loaded here by its path: the package itself is not
imported (its dependencies are not installed at build time).  An editable install reads
the resources from the checkout instead, so nothing is copied there.
"""

from __future__ import annotations

import importlib.util
import shutil
from pathlib import Path
from types import ModuleType

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent


def _resources_module() -> ModuleType:
    """``rattle_lab/_resources.py``, loaded on its own (it imports only the standard library)."""
    spec = importlib.util.spec_from_file_location("_rattle_lab_resources",
                                                  ROOT / "rattle_lab" / "_resources.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


class BuildPyWithResources(build_py):
    """``build_py`` that also copies the resource folders into ``rattle_lab/data``."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        for kind, sources in _resources_module().checkout_files(ROOT).items():
            target = Path(self.build_lib) / "rattle_lab" / "data" / kind
            target.mkdir(parents=True, exist_ok=True)
            for source in sources:
                shutil.copyfile(source, target / source.name)


setup(cmdclass={"build_py": BuildPyWithResources})
