"""Subcommands that live in their own modules; each has ``register(sub)`` and ``main(args)``,
and :mod:`jswim.cli` adds them with one line each."""
