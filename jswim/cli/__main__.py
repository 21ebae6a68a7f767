"""``python -m jswim.cli``: the ``jswim`` command."""

from jswim.cli import run

run()
