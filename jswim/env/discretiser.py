"""A world's discretiser for tabular learners: state -> table row, and the action codes offered.

Every world supplies one ([`Environment.cells`][jswim.env.base.Environment.cells]):

* [`Cells`][jswim.env.discretiser.Cells], the default, serves any world: each DOF's place ``j``
  on the K lattice read from its scaled value (the first ``n_dof`` entries of ``env.features``, in
  [-1, 1]), rows ``sum_d j_d (K + 1)**d`` (the joint corners at K = 1: 4 shapes alone, 16 for a
  pair, ``2**(2S)`` for S swimmers);
* [`PaperCells`][jswim.env.discretiser.PaperCells]: the paper's world, the corner (or lattice
  point) of `jswim.env`'s state, and the swimmer's offered ROCs
  ([`offered_rocs`][jswim.action_codes.offered_rocs]);
* [`WallCells`][jswim.env.discretiser.WallCells]: a scene with a wall, the joint corner times a
  height bin of swimmer 1 (``HEIGHT_EDGES``).

A world of its own may return a subclass of its own.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax.numpy as jnp
from jax import Array

from jswim.action_codes import offered_rocs

#: Height-bin edges of the tabular learner's wall state (a, swimmer 1's middle sphere above the
#: wall): about doubling, so the bins are as fine near the wall as the wall's effect is strong.
HEIGHT_EDGES = (2.0, 3.5, 6.0, 10.0, 17.0, 30.0)


def offered(j: Array, n_dof: int, action_set: str, roc_levels: int = 1) -> Array:
    """Boolean mask of the integer codes offered at lattice positions ``j`` ``(n_dof,)``: every code
    (``"all"``), or the shape-changing ones (a positive ROC below the top, a negative one above
    the bottom)."""
    width = 2 * roc_levels + 1
    if action_set == "all":
        return jnp.ones((width * n_dof,), bool)
    roc = jnp.arange(width * n_dof) % width - roc_levels
    level = jnp.repeat(j, width, total_repeat_length=width * n_dof)
    if roc_levels == 1:
        return roc == 1 - 2 * level  # +1 from lo, -1 from hi
    return ((roc > 0) & (level < roc_levels)) | ((roc < 0) & (level > 0))


def corner(j: Array, roc_levels: int = 1) -> Array:
    """Table row of lattice positions ``j``: ``sum_d j_d (K + 1)**d`` (K = 1: the corner index
    ``sum_d level_d 2**d``)."""
    base = (roc_levels + 1) ** jnp.arange(j.shape[-1], dtype=jnp.int32)
    return jnp.sum(j * base, dtype=jnp.int32)


def positions(state: Any, roc_levels: int) -> Array:
    """A `jswim.env` state's lattice positions ``j`` (int32, ``(n_dof,)``): its levels when
    ``K = 1``, else ``round(K frac)`` (every state reached from a corner by lattice codes lies on
    the lattice)."""
    if roc_levels == 1:
        return state.levels
    return jnp.round(state.frac * roc_levels).astype(jnp.int32)


def restrict(mask: Array, rocs: tuple[int, ...], n_dof: int, roc_levels: int = 1) -> Array:
    """``mask`` over codes, restricted to the ROCs ``k`` in ``rocs``."""
    roc_ok = jnp.zeros(2 * roc_levels + 1, bool).at[jnp.asarray(rocs) + roc_levels].set(True)
    return mask & jnp.tile(roc_ok, n_dof)


def offered_mask(
    levels: Array,
    n_dof: int,
    action_set: str,
    rocs: tuple[int, ...] | None = None,
    roc_levels: int = 1,
) -> Array:
    """The paper's swimmer's [`offered`][jswim.env.discretiser.offered], restricted to the ROCs
    offered (default [`offered_rocs`][jswim.action_codes.offered_rocs]: all three for two DOFs, +-1
    for more; every ``k`` in ``-K..K`` on a ROC lattice, 0 left out for more DOFs)."""
    rocs = offered_rocs(n_dof, roc_levels) if rocs is None else rocs
    return restrict(offered(levels, n_dof, action_set, roc_levels), rocs, n_dof, roc_levels)


@dataclasses.dataclass(frozen=True)
class Cells:
    """The default discretiser of a world (module docs); static and hashable like the world."""

    env: Any

    @property
    def n_cells(self) -> int:
        """Rows of the table."""
        return (self.env.roc_levels + 1) ** self.env.n_dof

    def positions(self, state: Any, params: Any) -> Array:
        """Each DOF's lattice position ``j`` in ``0..K`` (int32, ``(n_dof,)``)."""
        f = self.env.features(state, params)[: self.env.n_dof]
        return jnp.round((f + 1.0) * (0.5 * self.env.roc_levels)).astype(jnp.int32)

    def cell(self, state: Any, j: Array, params: Any) -> Array:
        """The table row of ``state`` (at positions ``j``)."""
        return corner(j, self.env.roc_levels)

    def mask(
        self, j: Array, params: Any, action_set: str, rocs: tuple[int, ...] | None = None
    ) -> Array:
        """The codes offered at ``j`` (``rocs``: the ROCs ``k`` offered, default every one)."""
        env = self.env
        mask = offered(j, env.n_dof, action_set, env.roc_levels)
        return mask if rocs is None else restrict(mask, rocs, env.n_dof, env.roc_levels)


@dataclasses.dataclass(frozen=True)
class PaperCells(Cells):
    """The paper's world: the corner (or lattice point) of `jswim.env`'s state, and by
    default the swimmer's offered ROCs ([`offered_mask`][jswim.env.discretiser.offered_mask])."""

    def positions(self, state: Any, params: Any) -> Array:
        return positions(state, self.env.roc_levels)

    def mask(
        self, j: Array, params: Any, action_set: str, rocs: tuple[int, ...] | None = None
    ) -> Array:
        return offered_mask(j, self.env.n_dof, action_set, rocs, self.env.roc_levels)


@dataclasses.dataclass(frozen=True)
class WallCells(Cells):
    """A scene with a wall: the joint corner times the height bin of swimmer 1's middle sphere."""

    @property
    def n_cells(self) -> int:
        return super().n_cells * (len(HEIGHT_EDGES) + 1)

    def cell(self, state: Any, j: Array, params: Any) -> Array:
        h = jnp.searchsorted(
            jnp.asarray(HEIGHT_EDGES, state.centre.dtype), state.centre[0, 1]
        ).astype(jnp.int32)
        return super().cell(state, j, params) * (len(HEIGHT_EDGES) + 1) + h
