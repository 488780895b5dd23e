"""``rattle-lab model ...``: the SDF model, its analysis and the plate model.

Sub-commands are registered by their own modules (listed below) so that each
stays one thin layer over one library function.
"""

from __future__ import annotations

import argparse
import importlib

#: Modules adding ``model`` sub-commands.
MODEL_COMMAND_MODULES: tuple[str, ...] = (
    "rattle_lab.cli._model_run",
    "rattle_lab.cli._model_plate",
    "rattle_lab.cli._model_orbits",
    "rattle_lab.cli._model_sweep",
    "rattle_lab.cli._model_modal",
)


def register(sub: argparse._SubParsersAction) -> None:  # type: ignore[type-arg]
    parser = sub.add_parser("model", help="the nondimensional SDF impact model and the plate model",
                            description="The SDF impact oscillator, its analysis, and plate modal data.")
    model_sub = parser.add_subparsers(dest="model_command", metavar="MODEL_COMMAND")
    for name in MODEL_COMMAND_MODULES:
        importlib.import_module(name).register(model_sub)

    def _no_sub(args: argparse.Namespace) -> int:
        parser.print_help()
        return 2

    parser.set_defaults(func=_no_sub)
