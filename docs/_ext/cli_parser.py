"""The parser of the ``obsdesign`` command as the CLI reference reads it (sphinx-argparse).

:func:`parser` is :func:`obsdesign.cli.build_parser` with the help texts' ``|S|``-style bars
escaped (sphinx-argparse reads help as reStructuredText, where ``|S|`` is a substitution); the
texts are the parser's own, nothing is written twice.
"""

from __future__ import annotations

import argparse

from api_docstrings import escape_bars

from obsdesign.cli import build_parser


def _escape(text):
    return "\n".join(escape_bars(line) for line in text.split("\n")) if isinstance(text, str) else text


def _walk(p: argparse.ArgumentParser) -> None:
    p.description, p.epilog = _escape(p.description), _escape(p.epilog)
    for action in p._actions:
        action.help = _escape(action.help)
        if isinstance(action, argparse._SubParsersAction):
            for choice in action._choices_actions:
                choice.help = _escape(choice.help)
            for sub in action.choices.values():
                _walk(sub)


def parser() -> argparse.ArgumentParser:
    """``obsdesign``'s parser, help texts escaped for reStructuredText."""
    p = build_parser()
    _walk(p)
    return p
