"""A swimmer's start: its initial corner of the DOF cube, as users write it (no JAX).

Shared by the paper's world ([`jswim.env.make_params`][jswim.env.params.make_params]) and the
scenes ([`jswim.scenes.scene_params`][jswim.scenes.scene_parameters.scene_params]), which sits
below the worlds, so it lives below both.
"""

from __future__ import annotations

from collections.abc import Sequence

from jswim.errors import ConfigError

__all__ = ["all_inits", "parse_init"]


def parse_init(init: Sequence[int] | str | None, n_dof: int) -> tuple[int, ...]:
    """Initial levels as a tuple of 0/1 (or -1 for random) of length ``n_dof``.

    Parameters
    ----------
    init : sequence of int, str or None
        Levels per DOF (0 lo, 1 hi, -1 random), a sign string (``"+-"``: + = hi, - = lo), or
        ``"random"``; ``None``: every DOF at ``hi``.
    n_dof : int
        The swimmer's number of DOFs.

    Returns
    -------
    tuple of int
        ``n_dof`` levels, each 0, 1 or -1.

    Raises
    ------
    ConfigError
        Any other value, or the wrong number of levels.
    """
    if init is None:
        return (1,) * n_dof
    if isinstance(init, str):
        text = init.strip().lower()
        if text == "random":
            return (-1,) * n_dof
        if text and all(ch in "+-" for ch in text):
            init = tuple(1 if ch == "+" else 0 for ch in text)
        else:
            raise ConfigError(
                f"init must be levels like (1, 0), a sign string like '+-', or 'random'; got {init!r}"
            )
    try:
        levels = tuple(int(v) for v in init)
    except (TypeError, ValueError):
        raise ConfigError(f"init must be a sequence of 0/1 levels, got {init!r}") from None
    if len(levels) != n_dof or any(v not in (0, 1, -1) for v in levels):
        raise ConfigError(
            f"init must give {n_dof} levels, each 0 (lo), 1 (hi) or -1 (random); got {init!r}"
        )
    return levels


def all_inits(n_dof: int) -> list[tuple[int, ...]]:
    """Every corner of the DOF cube, e.g. the four initial configurations of a 2-DOF swimmer."""
    return [tuple((c >> k) & 1 for k in range(n_dof)) for c in range(2**n_dof)][::-1]
