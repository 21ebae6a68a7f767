"""Exceptions that describe a user mistake (the CLI turns them into a one-line message)."""


class ConfigError(ValueError):
    """A parameter has a bad value; the message names the parameter and what to change."""
