"""Command-line commands: thin layers over the library, one module per capability.

Each module imports the Typer apps of :mod:`probedyn.commands._apps` and decorates commands
on them; :mod:`probedyn.cli` imports the modules listed in ``COMMAND_MODULES``.
"""

COMMAND_MODULES = [
    "probedyn.commands.report",
    "probedyn.commands.modal",
    "probedyn.commands.smart",
    "probedyn.commands.friction",
    "probedyn.commands.contact",
    "probedyn.commands.stickslip",
    "probedyn.commands.push",
    "probedyn.commands.diagnose",
    "probedyn.commands.piezo",
    "probedyn.commands.place",
    "probedyn.commands.reduced",
    "probedyn.commands.track",
]
