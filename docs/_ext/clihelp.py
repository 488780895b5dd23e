"""Sphinx directive ``rattle-lab-help``: the ``--help`` text of a ``rattle-lab`` command.

``.. rattle-lab-help:: model sweep`` inserts what ``rattle-lab model sweep --help`` prints,
taken from the parser itself (:func:`rattle_lab.cli.build_parser`), so the reference cannot
drift from the program.  A command that does not exist fails the build.
"""

from __future__ import annotations

import argparse
import os

from docutils import nodes
from docutils.parsers.rst import Directive
from sphinx.application import Sphinx


def _help_text(words: list[str]) -> str:
    from rattle_lab.cli import build_parser

    os.environ["COLUMNS"] = "92"  # argparse wraps to the terminal width: fix it for the page
    parser = build_parser()
    for word in words:
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        if not subs or word not in subs[0].choices:
            raise ValueError(f"rattle-lab {' '.join(words)}: no such command")
        parser = subs[0].choices[word]
    return parser.format_help()


class RattleLabHelp(Directive):
    required_arguments = 0
    optional_arguments = 3
    has_content = False

    def run(self) -> list[nodes.Node]:
        try:
            text = _help_text(list(self.arguments))
        except ValueError as exc:
            raise self.error(str(exc)) from exc
        block = nodes.literal_block(text, text)
        block["language"] = "text"
        return [block]


def setup(app: Sphinx) -> dict[str, object]:
    app.add_directive("rattle-lab-help", RattleLabHelp)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
