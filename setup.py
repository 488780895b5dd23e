"""Build hook: ship the top-level resource folders inside the package.

All metadata lives in pyproject.toml.  This file only extends ``build_py`` so that a wheel
(``pip install .``) carries the scenes (``synthetic/*.toml``), the pipelines
(``pipelines/*.toml``), the mappings (``data_schema/mappings/*.toml``) and the record
schema (``data_schema/*.json``) as ``rattle_lab/data/<kind>/``, where
:mod:`rattle_lab._resources` finds them by name.  An editable install reads them from the
checkout instead, so nothing is copied there.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent

# kind -> (checkout folder, glob); keep in step with rattle_lab/_resources.py
RESOURCES = {
    "scenes": ("synthetic", "*.toml"),
    "pipelines": ("pipelines", "*.toml"),
    "mappings": ("data_schema/mappings", "*.toml"),
    "schema": ("data_schema", "*.json"),
}


class BuildPyWithResources(build_py):
    """``build_py`` that also copies the resource folders into ``rattle_lab/data``."""

    def run(self) -> None:
        super().run()
        if getattr(self, "editable_mode", False):
            return
        for kind, (folder, pattern) in RESOURCES.items():
            target = Path(self.build_lib) / "rattle_lab" / "data" / kind
            target.mkdir(parents=True, exist_ok=True)
            for source in sorted((ROOT / folder).glob(pattern)):
                shutil.copyfile(source, target / source.name)


setup(cmdclass={"build_py": BuildPyWithResources})
