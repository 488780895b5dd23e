"""Named resources shipped with rattle_lab: scenes, pipelines, mappings and the record schema.

The source checkout keeps them in top-level folders (``synthetic/``, ``pipelines/``,
``data_schema/mappings/``, ``data_schema/``); the build (``setup.py``) copies them into the
package as ``rattle_lab/data/<kind>/``, so a wheel installed with ``pip install .`` can find
them by name from any folder.  An editable install reads them from the checkout instead.

========== ========================== ============
kind       checkout folder            file suffix
========== ========================== ============
scenes     ``synthetic/``             ``.toml``
pipelines  ``pipelines/``             ``.toml``
mappings   ``data_schema/mappings/``  ``.toml``
schema     ``data_schema/``           ``.json``
========== ========================== ============

A name is a file's stem (``thesis_cfcf_1p3mm``) or its file name
(``thesis_cfcf_1p3mm.toml``).  An existing file path always wins over a name: callers
look a name up only when the path they were given does not exist.

Examples
--------
>>> find_resource("pipelines", "full_campaign").name
'full_campaign.toml'
>>> "default" in resource_names("scenes")
True
>>> find_resource("scenes", "no_such_scene") is None
True
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

__all__ = ["RESOURCE_KINDS", "find_resource", "not_found_hint", "read_pipeline_toml", "resource_dirs",
           "resource_names"]

#: kind -> (folder of the source checkout, relative to its root; file suffix)
RESOURCE_KINDS: dict[str, tuple[str, str]] = {
    "scenes": ("synthetic", ".toml"),
    "pipelines": ("pipelines", ".toml"),
    "mappings": ("data_schema/mappings", ".toml"),
    "schema": ("data_schema", ".json"),
}

_PACKAGE_DATA = Path(__file__).resolve().parent / "data"


def _checkout_root() -> Path | None:
    """The source checkout this package was imported from, or None for an installed wheel."""
    root = _PACKAGE_DATA.parents[1]
    return root if (root / "pyproject.toml").is_file() else None


def resource_dirs(kind: str) -> list[Path]:
    """The folders searched for resources of ``kind``, in order (existing ones only).

    Raises
    ------
    KeyError
        If ``kind`` is not one of :data:`RESOURCE_KINDS`.
    """
    folder, _ = RESOURCE_KINDS[kind]
    dirs = [_PACKAGE_DATA / kind]
    root = _checkout_root()
    if root is not None:
        dirs.append(root / folder)
    return [d for d in dirs if d.is_dir()]


def resource_names(kind: str) -> list[str]:
    """The names (file stems) of the resources of ``kind`` available, sorted and unique."""
    _, suffix = RESOURCE_KINDS[kind]
    return sorted({p.stem for d in resource_dirs(kind) for p in d.glob(f"*{suffix}")})


def find_resource(kind: str, name: str) -> Path | None:
    """The file of the resource ``name`` of ``kind``, or None if there is none.

    ``name`` must be a bare name (no folder part); the suffix is optional.
    """
    if not name or Path(name).name != name:
        return None
    _, suffix = RESOURCE_KINDS[kind]
    file_name = name if name.endswith(suffix) else name + suffix
    for folder in resource_dirs(kind):
        candidate = folder / file_name
        if candidate.is_file():
            return candidate
    return None


_SINGULAR = {"scenes": "scene", "pipelines": "pipeline", "mappings": "mapping",
             "schema": "schema"}


def not_found_hint(kind: str, name: str | os.PathLike[str]) -> str:
    """Why ``name`` was not found, as a file or a shipped resource, with the shipped names
    and the closest one.

    >>> not_found_hint("scenes", "defualt").split(";")[0]
    "no such file, and no shipped scene 'defualt'"
    >>> "closest: 'default'" in not_found_hint("scenes", "defualt")
    True
    """
    import difflib

    if Path(name).parent != Path("."):  # a path, not a name: the file is what is missing
        return "No such file or directory"
    what = _SINGULAR[kind]
    names = resource_names(kind)
    stem = Path(name).stem if Path(name).suffix == RESOURCE_KINDS[kind][1] else Path(name).name
    close = difflib.get_close_matches(stem, names, n=1, cutoff=0.5)
    hint = f"no such file, and no shipped {what} {stem!r}; shipped: {', '.join(names)}"
    return hint + (f" (closest: {close[0]!r})" if close else "")


def read_pipeline_toml(path: str | os.PathLike[str]) -> tuple[dict[str, Any], str]:
    """The parsed TOML of a pipeline file, or of a pipeline shipped with rattle_lab by name.

    Returns ``(document, path)``, ``path`` as resolved (for messages).

    Raises
    ------
    ParameterError
        If the file cannot be read or is not TOML.
    """
    import tomllib

    from rattle_lab.exceptions import ParameterError

    if not Path(path).exists():  # a pipeline shipped with rattle_lab, by name
        found = find_resource("pipelines", str(path))
        if found is None:
            raise ParameterError(f"{path}: cannot read pipeline TOML: "
                                 f"{not_found_hint('pipelines', path)}")
        path = found
    try:
        return tomllib.loads(Path(path).read_text(encoding="utf-8")), str(path)
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
        raise ParameterError(f"{path}: cannot read pipeline TOML: {why}") from exc
