"""Environment parameters: the swimmer, the noise level, the target direction, the start, and the
action space (``roc_levels``, ``diagonal``)."""

from __future__ import annotations

import dataclasses
import functools
import warnings
from typing import Any
from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np

from jswim.action_codes import check_roc_levels as _check_roc_levels
from jswim.env.flows import Flow, Uniform
from jswim.scenes.ranges import ModelRangeWarning
from jswim.errors import ConfigError, check_zeta
from jswim.start_levels import parse_init
from jswim.swimmers.models import SwimmerModel, make_model


@functools.partial(
    jax.tree_util.register_dataclass,
    data_fields=["zeta", "direction", "init"],
    meta_fields=["model", "roc_levels", "diagonal", "flow"],
)
@dataclasses.dataclass(frozen=True)
class EnvParams:
    """Environment parameters.

    Attributes
    ----------
    model : SwimmerModel
        Static swimmer description (kind, number of DOFs, limits).
    zeta : float or Array
        Noise level, >= 0 (0 = the noiseless swimmer).
    direction : float or Array
        Target direction, +1 for +e_x, -1 for -e_x (sign of the reward ``progress``).
    init : Array, int32 (n_dof,)
        Initial DOF levels: 0 = lo, 1 = hi, -1 = drawn at random by [`jswim.env.reset`][jswim.env.state.reset].
    roc_levels : int
        K (static): integer action codes carry ROC ``k / K`` with ``k`` in ``-K..K``
        (``n_dof (2K + 1)`` codes, [`jswim.env.encode_action`][jswim.action_codes.encode_action]). K = 1 is the paper's
        ROC in {-1, 0, 1}. Float ROC vectors are accepted whatever K is.
    diagonal : bool
        Static. Whether a float ROC vector may move several DOFs at once (a diagonal stroke,
        through the integrator). Off: only its first non-zero entry moves (S2 of the paper:
        one DOF at a time).
    flow : Flow or None
        Static. The background flow the swimmer moves in (`jswim.env.flows`); ``None``, the
        default, is still fluid (the paper's world, every number as without it). Each step lasts
        one unit of time ``tau``, so a `Uniform` flow adds exactly ``u`` to every step's
        displacement (Galilean invariance), after the paper's noise on the stroke's own; any
        other flow is integrated through the step (`jswim.env.stepping.flow_step`).
    """

    model: SwimmerModel
    zeta: Any = 0.0
    direction: Any = 1.0
    init: Any = None
    roc_levels: int = 1
    diagonal: bool = False
    flow: Any = None

    def replace(self, **changes: Any) -> EnvParams:
        """A copy with some fields changed (fields may be traced arrays)."""
        return dataclasses.replace(self, **changes)

    @property
    def n_dof(self) -> int:
        return self.model.n_dof

    @property
    def n_actions(self) -> int:
        """Number of integer action codes, ``n_dof (2K + 1)`` (``3 n_dof`` for K = 1)."""
        return (2 * self.roc_levels + 1) * self.model.n_dof

    @property
    def lo(self) -> float:
        return self.model.lo

    @property
    def hi(self) -> float:
        return self.model.hi


def make_params(
    swimmer: str | SwimmerModel = "purcell",
    *,
    zeta: float = 0.0,
    direction: int | str = 1,
    init: Sequence[int] | str | None = None,
    roc_levels: int = 1,
    diagonal: bool = False,
    flow: Any = None,
    **model_kwargs: Any,
) -> EnvParams:
    """Validated environment parameters with the paper's defaults.

    Parameters
    ----------
    swimmer : str or SwimmerModel
        ``"purcell"``, ``"ng"``, ``"nlink"`` or ``"nsphere"``; model options (``d_max``,
        ``d_min``, ``n_links``, ``n_spheres``, ``xi_ratio``) go by keyword, see
        [`jswim.swimmers.models.make_model`][jswim.swimmers.models.make_model].
    zeta : float
        Noise level, >= 0.
    direction : int or str
        +1 / ``"+x"`` or -1 / ``"-x"``.
    init : sequence of int or str, optional
        Initial configuration: levels per DOF as 0/1 (``(1, 1)``), as a sign string (``"+-"``:
        + = hi, - = lo), or ``"random"``. Default: every DOF at ``hi``, the (+, +) start.
    roc_levels : int
        K >= 1: integer action codes mean ROC ``k / K``, ``k`` in ``-K..K`` (1: the paper's).
    diagonal : bool
        Allow float ROC vectors that move several DOFs at once (default False).
    flow : Flow, optional
        A background flow (`jswim.env.flows`; planar swimmers, or a stream along the line of a
        line swimmer: `check_flow`). A `Uniform` flow adds ``u`` to each step's table
        displacement; the others add what the flow tables give for the step
        (`jswim.env.flow_steps`), or integrate it ([`flow_step`][jswim.env.stepping.flow_step])
        in an `jswim.env.flow_steps.Integrated` flow or off the tables.

    Raises
    ------
    ConfigError
        For any invalid value.
    """
    model = swimmer if isinstance(swimmer, SwimmerModel) else make_model(swimmer, **model_kwargs)
    check_flow(flow, model, diagonal)
    return EnvParams(
        model=model,
        zeta=check_zeta(zeta),
        direction=float(parse_direction(direction)),
        init=np.asarray(parse_init(init, model.n_dof), np.int32),
        roc_levels=check_roc_levels(roc_levels),
        diagonal=bool(diagonal),
        flow=flow,
    )


#: A flow whose velocity gradient (`jswim.env.flows.Flow.max_gradient`) passes this (``1 / tau``)
#: turns the body by more than ~0.1 rad a step, beyond what the flow tables model (their error is
#: third order in it: docs/physics.md, "Background flows"); it warns.
MAX_TABLE_GRADIENT = 0.1


def check_flow(flow: Any, model: SwimmerModel, diagonal: bool = False) -> None:
    """Refuse what a world cannot step in: a flow that is not a `jswim.env.flows` flow, a
    swimmer that moves on a line in any flow but a uniform stream along its line, or diagonal
    strokes in a flow that is not uniform.

    A stream along the line carries every sphere, and so the force-free body, at ``u`` whatever
    the mobility (Galilean invariance): exact. Any other flow would carry the body off its line
    or turn it, which a line world does not model.

    Raises
    ------
    ConfigError
        Any of these, in one line.
    """
    if flow is None:
        return
    if not isinstance(flow, Flow):
        raise ConfigError(
            f"flow must be a jswim.env.flows flow (Uniform, Shear, Poiseuille, TaylorGreen), "
            f"got {flow!r}"
        )
    if not model.planar and not (isinstance(flow, Uniform) and float(flow.u[1]) == 0.0):
        raise ConfigError(
            f"{model.label} moves on a line: it takes a Uniform((ux, 0)) stream along it, not "
            f"{flow!r} (a planar swimmer takes any flow)"
        )
    if flow.kind != "integrated" and flow.max_gradient > MAX_TABLE_GRADIENT:
        warnings.warn(
            f"{flow!r} has a velocity gradient of {flow.max_gradient:.3g} per step, beyond the "
            f"flow tables' range (up to {MAX_TABLE_GRADIENT}; docs/physics.md): wrap it in "
            "jswim.env.flow_steps.Integrated to step through the RK4 reference",
            ModelRangeWarning,
            stacklevel=3,
        )
    if diagonal and not isinstance(flow, Uniform):
        raise ConfigError(
            f"diagonal strokes are offered in a uniform flow only, not in {flow!r} (its steps "
            "follow one DOF's move at a time)"
        )


def check_roc_levels(k: Any) -> int:
    """``k`` as an int if it is a valid number of ROC levels K (the rule of
    [`jswim.action_codes.check_roc_levels`][jswim.action_codes.check_roc_levels], with the message naming ``roc_levels``)."""
    return _check_roc_levels(k, "roc_levels")


def parse_direction(direction: int | str) -> int:
    """``+1`` / ``"+x"`` / ``"+"`` -> 1 and ``-1`` / ``"-x"`` / ``"-"`` -> -1."""
    table = {"+x": 1, "+": 1, "x": 1, "+1": 1, "1": 1, "-x": -1, "-": -1, "-1": -1}
    if isinstance(direction, str) and direction.strip().lower() in table:
        return table[direction.strip().lower()]
    if not isinstance(direction, (str, bool)) and direction in (1, -1):
        return int(direction)
    raise ConfigError(f"direction must be +1 ('+x') or -1 ('-x'), got {direction!r}")


def is_batched(params: EnvParams) -> bool:
    """Whether any data leaf of ``params`` carries a batch axis."""
    return jnp.ndim(params.zeta) > 0 or jnp.ndim(params.direction) > 0 or jnp.ndim(params.init) > 1


def param_axes(params: EnvParams) -> EnvParams:
    """``vmap`` axes of ``params``: 0 for batched leaves, None for shared ones."""
    return params.replace(
        zeta=0 if jnp.ndim(params.zeta) > 0 else None,
        direction=0 if jnp.ndim(params.direction) > 0 else None,
        init=0 if jnp.ndim(params.init) > 1 else None,
    )


def broadcast_params(params: EnvParams, size: int, **changes: Any) -> EnvParams:
    """Broadcast the data leaves of ``params`` (after ``changes``) to a leading axis of ``size``.

    ``changes`` may give per-swimmer values, e.g. ``zeta=np.linspace(0, 3, size)``.
    """
    n = params.model.n_dof
    fields = {"zeta": params.zeta, "direction": params.direction, "init": params.init, **changes}
    dtype = jnp.result_type(float)
    return params.replace(
        zeta=jnp.broadcast_to(jnp.asarray(fields["zeta"], dtype), (size,)),
        direction=jnp.broadcast_to(jnp.asarray(fields["direction"], dtype), (size,)),
        init=jnp.broadcast_to(jnp.asarray(fields["init"], jnp.int32), (size, n)),
    )
