"""``python -m jswim``: the ``jswim`` command (the bench starts its studies this way)."""

from jswim.cli import run

run()
