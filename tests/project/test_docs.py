"""README.md and docs/: the first page stays short, links resolve, named commands exist.

Fast checks of the text a user reads (a second or two: two ``--help`` calls of the installed
``rattle-lab``); the Sphinx build itself (``make docs``, warnings are errors) runs in
``make lint``.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest
from conftest import CHECKOUT, RATTLE_LAB

README = CHECKOUT / "README.md"
DOCS = CHECKOUT / "docs"
#: The pages a user reads: README.md and every Markdown or reST page of docs/ (not the build).
PAGES = [README, *sorted(p for p in DOCS.rglob("*") if p.suffix in (".md", ".rst")
                         and "_build" not in p.parts)]

# [text](target) in Markdown, outside code; the target up to whitespace or ")"
_MD_LINK = re.compile(r"(?<!!)\[[^\]\n]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
_MD_IMAGE = re.compile(r"!\[[^\]\n]*\]\(([^)\s]+)\)")
# reST: .. image:: path, .. figure:: path, .. literalinclude:: path, .. include:: path
_RST_FILE = re.compile(r"^\s*\.\. (?:image|figure|literalinclude|include)::\s*(\S+)", re.M)
# MyST: ```{literalinclude} path / ```{include} path
_MYST_FILE = re.compile(r"^```\{(?:literalinclude|include|image|figure)\}\s*(\S+)", re.M)
_FENCE = re.compile(r"^```.*?^```", re.M | re.S)
_INLINE_CODE = re.compile(r"`[^`\n]*`")


def _prose(text: str) -> str:
    """``text`` without fenced code blocks and inline code (links there are not links)."""
    return _INLINE_CODE.sub("", _FENCE.sub("", text))


def _relative_targets(page: Path) -> list[str]:
    text = page.read_text(encoding="utf-8")
    found = _MYST_FILE.findall(text)
    if page.suffix == ".md":
        prose = _prose(text)
        found += _MD_LINK.findall(prose) + _MD_IMAGE.findall(prose)
    else:
        found += _RST_FILE.findall(text)
    return [t for t in found if not re.match(r"^[a-z][a-z0-9+.-]*:", t)  # http:, mailto:
            and not t.startswith("#")]


def test_readme_is_a_first_page() -> None:
    """The README stays a first page: at most 200 lines (issue 25)."""
    n = len(README.read_text(encoding="utf-8").splitlines())
    assert n <= 200, f"README.md has {n} lines (at most 200): move the detail into docs/"


def test_checker_sees_links() -> None:
    """The link finder finds links, and ignores those in code (else the next test is empty)."""
    sample = ("see [a](x/y.md) and ![img](p.png), `[not](code.md)`\n"
              "```\n[nor](fenced.md)\n```\n[web](https://example.org) [here](#anchor)\n")
    assert _MD_LINK.findall(_prose(sample)) == ["x/y.md", "https://example.org", "#anchor"]
    assert _MD_IMAGE.findall(_prose(sample)) == ["p.png"]
    assert len(_relative_targets(README)) >= 10


@pytest.mark.parametrize("page", PAGES, ids=lambda p: str(p.relative_to(CHECKOUT)))
def test_relative_links_resolve(page: Path) -> None:
    """Every relative link and included file of a page names a file or folder that exists."""
    missing = []
    for target in _relative_targets(page):
        path = target.split("#", 1)[0]
        if path and not (page.parent / path).exists():
            missing.append(target)
    assert not missing, f"{page.relative_to(CHECKOUT)}: links to nothing: {missing}"


def _help(*words: str) -> str:
    proc = subprocess.run([str(RATTLE_LAB), *words, "--help"], capture_output=True, text=True,
                          timeout=60)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout


def _commands_in(help_text: str) -> set[str]:
    """The sub-commands an argparse ``--help`` lists: ``{a,b,c}`` or the indented names."""
    names: set[str] = set()
    for braces in re.findall(r"\{([a-z0-9,-]+)\}", help_text):
        names.update(braces.split(","))
    names.update(re.findall(r"^    ([a-z][a-z0-9-]*)(?:\s|$)", help_text, re.M))
    return names


def test_named_commands_exist() -> None:
    """Every ``rattle-lab COMMAND`` (and ``rattle-lab model COMMAND``) named in README.md or
    docs/ is a command the installed ``rattle-lab --help`` lists."""
    top = _commands_in(_help())
    model = _commands_in(_help("model"))
    assert {"ingest", "fit", "model"} <= top and {"run", "sweep"} <= model, (top, model)
    unknown = set()
    named = 0
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for first, second in re.findall(r"rattle-lab ([a-z][a-z0-9-]*)(?: ([a-z][a-z0-9-]*))?",
                                        text):
            named += 1
            if first not in top:
                unknown.add(f"{page.name}: rattle-lab {first}")
            elif first == "model" and second and second not in model:
                unknown.add(f"{page.name}: rattle-lab model {second}")
    assert named >= 20
    assert not unknown, sorted(unknown)
