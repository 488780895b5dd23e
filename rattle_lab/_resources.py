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
(``thesis_cfcf_1p3mm.toml``).  An existing file path always wins over a name:
:func:`resource_file` and :func:`resolve_resource` (what the loaders of scenes,
mappings, pipelines and the schema call) look a name up only when the path they were
given does not exist.  :data:`RESOURCE_KINDS` is also the wheel's resource list:
``setup.py`` copies :func:`checkout_files` into the package.

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

__all__ = ["RESOURCE_KINDS", "checkout_files", "find_resource", "not_found_hint", "read_pipeline_toml",
           "resolve_resource", "resource_dirs", "resource_file", "resource_names"]

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


def checkout_files(root: Path) -> dict[str, list[Path]]:
    """kind -> the files of the source checkout at ``root`` that the wheel ships as that kind.

    ``setup.py`` copies them to ``rattle_lab/data/<kind>/`` (it loads this module by its
    path, so the list is kept in one place).
    """
    return {kind: sorted((root / folder).glob(f"*{suffix}"))
            for kind, (folder, suffix) in RESOURCE_KINDS.items()}


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


def resource_file(kind: str, path_or_name: str | os.PathLike[str]) -> Path | None:
    """The file ``path_or_name`` stands for: the path if it exists, else the resource of
    ``kind`` shipped under that name, else None."""
    path = Path(path_or_name)
    if path.exists():
        return path
    return find_resource(kind, str(path_or_name))


def resolve_resource(kind: str, path_or_name: str | os.PathLike[str], error: type[Exception],
                     action: str) -> Path:
    """:func:`resource_file`, or ``error("<path_or_name>: <action>: <why>")`` if there is none.

    ``why`` (:func:`not_found_hint`) lists the shipped names and the closest one.

    >>> resolve_resource("pipelines", "full_campaign", ValueError, "cannot read").name
    'full_campaign.toml'
    >>> resolve_resource("scenes", "defualt", ValueError, "cannot read the scene")
    Traceback (most recent call last):
    ...
    ValueError: defualt: cannot read the scene: no such file, and no shipped scene 'defualt'; ...
    """
    found = resource_file(kind, path_or_name)
    if found is None:
        raise error(f"{path_or_name}: {action}: {not_found_hint(kind, path_or_name)}")
    return found


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

    found = resolve_resource("pipelines", path, ParameterError, "cannot read pipeline TOML")
    if found != Path(path):  # a pipeline shipped with rattle_lab, by name
        path = found
    try:
        return tomllib.loads(Path(path).read_text(encoding="utf-8")), str(path)
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
        raise ParameterError(f"{path}: cannot read pipeline TOML: {why}") from exc
