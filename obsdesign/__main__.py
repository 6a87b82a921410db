"""``python -m obsdesign`` runs the command line."""

from .cli import run

run()
