"""The world protocol: what every environment of jswim offers the layers above it.

A world is a static, hashable object (a frozen dataclass: one compilation per world) in the
gymnax manner; its numbers travel separately as ``params`` (a pytree whose leaves may be
batched). Every world answers:

* ``reset(key, params) -> state`` and ``step(key, state, action, params) -> (state, StepInfo)``;
* ``advance(state, action, noise, params)``: the step for given noise draws ``(n_swimmers,)`` in
  [-1, 1] (what [`Environment.step`][jswim.env.base.Environment.step] draws from its key: [`Environment.noise`][jswim.env.base.Environment.noise]);
* ``observe(state, params) -> Observation``: what agents may see; ``features(state, params)``:
  the same as one flat float vector (the input of a policy network);
* ``action_space(params)`` (integer codes, [`Discrete`][jswim.env.base.Discrete]) and ``roc_space(params)`` (float
  ROC vectors, [`Box`][jswim.env.base.Box]), each with ``sample(key)`` as in gymnax;
* the sizes ``n_dof`` (joint DOFs of every swimmer), ``n_actions``, ``n_swimmers``, and
  ``default_params``.

An action is an integer code over the joint DOFs, ``(dof - 1)(2K + 1) + k + K`` (DOF 1-based,
ROC ``k / K``; swimmer ``s`` of a scene owns DOFs ``2s + 1, 2s + 2``), or a float ROC vector of
shape ``(n_dof,)`` in [-1, 1] (only its first non-zero entry moves unless the world allows
diagonal strokes). One [`StepInfo`][jswim.env.base.StepInfo] serves every world; ``progress`` is the reward of the
paper's task toward ``params.direction`` (+1: +x, -1: -x), a parameter of every world.

Worlds: [`jswim.env.swimmer_world.SwimmerWorld`][jswim.env.swimmer_world.SwimmerWorld] (the paper's swimmers alone in the fluid,
over `jswim.env`) and [`jswim.env.scene_world.SceneWorld`][jswim.env.scene_world.SceneWorld] (walls, obstacles, pairs,
over `jswim.scenes`); [`jswim.env.registry.make`][jswim.env.registry.make] builds either. A new world subclasses
[`Environment`][jswim.env.base.Environment] and fills in ``reset``, ``advance``, ``observe`` and the sizes (see
docs/design.md, *Adding a world*).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from jswim.env.discretiser import Cells


class StepInfo(NamedTuple):
    """What one step of any world did (``S`` swimmers).

    Attributes
    ----------
    displacement : Array (S, 2)
        Each swimmer's displacement ``(dx, dy)`` over the step, of the point
        `Observation.position` reports (the paper's centroid), lab frame, units of the
        world's length (link length or sphere radius ``a``); noisy when ``zeta > 0``. ``dy`` is
        the height change above a wall.
    progress : Array ()
        The reward: ``direction`` times the swimmers' mean ``dx``.
    stuck : Array () bool
        A non-zero ROC could not move its DOF at all (it sat at its limit); nothing moved.
    moved : Array () bool
        The shape changed.
    contact : Array () bool
        The move would have brought two surfaces too close; it was refused (False where nothing
        can be touched).
    gap : Array ()
        Smallest surface gap along the step (``inf`` where nothing can be touched).
    work : Array ()
        The work the step's strokes did on the fluid: the energy the step dissipates, all
        swimmers together ([`jswim.env.work`][jswim.env.work]). Units: ``xi_par a^3 / tau`` for
        link swimmers (Purcell's, longer chains; ``xi_par`` the bulk fluid's drag coefficient
        per length, ``a`` the link length) and ``6 pi mu a^3 / tau`` for sphere swimmers (NG;
        ``a`` the sphere radius), ``tau`` one step at ``|ROC| = 1``. It does not depend on the
        noise ``zeta`` (the paper perturbs the displacement only). Worlds that do not count
        energy leave the default ``nan`` (the scenes of `jswim.scenes` and any world a user
        registers without it): a ``nan`` sum says "not counted", never "free".
    """

    displacement: Array
    progress: Array
    stuck: Array
    moved: Array
    contact: Array
    gap: Array
    work: Array | float = math.nan


class Observation(NamedTuple):
    """What agents may see of a state (``S`` swimmers).

    Attributes
    ----------
    dofs : Array (n_dof,)
        Joint DOF values (hinge angles in rad, arm lengths in ``a``), swimmer by swimmer.
    position : Array (S, 2)
        Each swimmer's centroid ``(x, y)``; above a wall ``y`` is the height.
    orientation : Array (S,)
        Each swimmer's orientation (rad): the reference link's angle, or a scene swimmer's tilt
        from the wall plane.
    height : Array (S,)
        Each swimmer's height as its world records it, always given: a scene swimmer's middle
        sphere's ``z`` ([`jswim.scenes.SceneState`][jswim.scenes.scene_state.SceneState]), which
        the prompt's ``H`` shows; a swimmer in a plane seen from above (the paper's world,
        Purcell's swimmer in a plane parallel to a wall, a registered world's), which has no
        height of its own in the observation, its ``y`` in that plane (``position[:, 1]``).
        [`Scenery.side_view`][jswim.env.base.Scenery] says which of the two a world's is.
    target : TargetView or None
        A navigation world's current target: position, distance and bearing in the body frame
        ([`jswim.env.navigation.TargetView`][jswim.env.navigation.TargetView]); ``None``: the
        world has no target.
    """

    dofs: Array
    position: Array
    orientation: Array
    height: Array
    target: Any = None


class Scenery(NamedTuple):
    """What a world's pictures draw beside its swimmers' positions (the world supplies it, so a
    picture never asks which kind of world it holds).

    Attributes
    ----------
    model : SwimmerModel or None
        The swimmer whose body outline is drawn from the observed DOFs; ``None``: each swimmer is
        drawn as a marker at its position (a world of [`jswim.register_world`][jswim.env.registry.register_world]).
    wall : bool
        A plane wall at ``y = 0`` (the swimmers' heights are their ``y``).
    obstacles : tuple of (x, z, radius)
        Fixed spheres, in ``a``.
    plane_height : float or None
        The height (link lengths) of a planar swimmer's plane above a wall parallel to it, drawn
        from above; ``None``: no such wall.
    side_view : bool
        The swimmers move in a vertical plane, seen from the side (a scene's): ``position``'s
        ``y`` and ``height`` are heights and ``orientation`` a tilt from the wall plane. ``False``
        (the default): a plane seen from above, ``y`` lies in that plane and ``orientation`` is a
        heading; a scene row then records the plane's height (0 without a wall) and no tilt.
    """

    model: Any = None
    wall: bool = False
    obstacles: tuple[tuple[float, float, float], ...] = ()
    plane_height: float | None = None
    side_view: bool = False


class Discrete:
    """``n`` integer actions ``0 .. n - 1`` (gymnax's ``spaces.Discrete`` interface)."""

    def __init__(self, n: int, dtype: Any = jnp.int32) -> None:
        self.n = int(n)
        self.shape: tuple[int, ...] = ()
        self.dtype = dtype

    def sample(self, key: Array) -> Array:
        """A uniformly random action."""
        return jax.random.randint(key, self.shape, 0, self.n, self.dtype)

    def contains(self, x: Any) -> Array:
        x = jnp.asarray(x)
        return jnp.logical_and(x >= 0, x < self.n)

    def __repr__(self) -> str:
        return f"Discrete({self.n})"


class Box:
    """Real vectors in ``[low, high]`` of a fixed shape (gymnax's ``spaces.Box`` interface)."""

    def __init__(
        self, low: Any, high: Any, shape: tuple[int, ...], dtype: Any = jnp.float32
    ) -> None:
        self.low, self.high, self.shape, self.dtype = low, high, tuple(shape), dtype

    def sample(self, key: Array) -> Array:
        """A uniformly random vector."""
        return jax.random.uniform(key, self.shape, minval=self.low, maxval=self.high).astype(
            self.dtype
        )

    def contains(self, x: Any) -> Array:
        x = jnp.asarray(x)
        return jnp.logical_and(jnp.all(x >= self.low), jnp.all(x <= self.high))

    def __repr__(self) -> str:
        return f"Box({self.low}, {self.high}, {self.shape})"


@dataclasses.dataclass(frozen=True)
class Environment:
    """Base of every world (module docs). Subclasses are frozen dataclasses (static, hashable).

    Subclasses define ``n_dof``, ``n_swimmers``, ``roc_levels`` (K of the integer codes),
    ``default_params``, ``reset``, ``advance`` and ``observe``; ``step``, ``noise``, the spaces
    and ``n_actions`` come from here.
    """

    @property
    def n_dof(self) -> int:
        raise NotImplementedError

    def _repr_html_(self) -> str:
        """The world's swimmers, DOFs and actions, and a small picture of its start."""
        from jswim import reprs  # lazy: drawing loads matplotlib

        model = getattr(self, "model", None)  # the paper's swimmers: draw a typical bent shape
        body = None
        if model is not None:
            from jswim.swimmers.outline import outline  # lazy: only to draw

            body = outline(model, jnp.full(model.n_dof, model.lo + 0.8 * (model.hi - model.lo)))
        return reprs.world_html(self, body)

    @property
    def n_swimmers(self) -> int:
        return 1

    def scenery(self) -> Scenery:
        """What this world's pictures draw ([`Scenery`][jswim.env.base.Scenery]); default: each
        swimmer as a marker, no wall, no obstacle."""
        return Scenery()

    @property
    def roc_levels(self) -> int:
        return 1

    @property
    def n_actions(self) -> int:
        """Integer action codes: ``n_dof (2K + 1)``."""
        return self.n_dof * (2 * self.roc_levels + 1)

    @property
    def dof_names(self) -> tuple[str, ...]:
        """Joint DOF names ``D1 .. D<n_dof>`` (1-based, as prompts and replies name them)."""
        return tuple(f"D{i}" for i in range(1, self.n_dof + 1))

    @property
    def dof_range(self) -> tuple[float, float]:
        """The interval ``(lo, hi)`` each DOF of [`observe`][jswim.env.scene_world.SceneWorld.observe] stays in, what an LLM's prompt
        states of a world of [`jswim.register_world`][jswim.env.registry.register_world] ([`jswim.agents.world_view.model`][jswim.agents.world_view.model]);
        default ``(0.0, 1.0)``: DOFs observed as their places in their ranges. The paper's
        swimmers' ranges are their models' ([`SwimmerModel`][jswim.swimmers.models.SwimmerModel]
        ``lo``, ``hi``), which the agents read instead."""
        return (0.0, 1.0)

    @property
    def dof_swimmer(self) -> tuple[int, ...]:
        """The swimmer (0-based) that owns each joint DOF: swimmer ``s`` owns ``n_dof / n_swimmers``
        consecutive DOFs (a scene's swimmer ``s``: DOFs ``2s + 1, 2s + 2``)."""
        per = self.n_dof // self.n_swimmers
        return tuple(i // per for i in range(self.n_dof))

    @property
    def default_params(self) -> Any:
        raise NotImplementedError

    def reset(self, key: Array, params: Any) -> Any:
        raise NotImplementedError

    def advance(self, state: Any, action: Array, noise: Array, params: Any) -> tuple[Any, StepInfo]:
        raise NotImplementedError

    def observe(self, state: Any, params: Any) -> Observation:
        raise NotImplementedError

    def dtype(self, state: Any) -> Any:
        """The working float dtype of ``state`` (the dtype of its first float leaf)."""
        return next(
            leaf.dtype
            for leaf in jax.tree.leaves(state)
            if jnp.issubdtype(leaf.dtype, jnp.floating)
        )

    def noise(self, key: Array, state: Any) -> Array:
        """The step's noise variables ``Y ~ U[-1, 1]``, one per swimmer ``(n_swimmers,)``; one
        swimmer's is ``uniform(key, ())``, the draw of [`jswim.env.step`][jswim.env.stepping.step]."""
        dtype = self.dtype(state)
        if self.n_swimmers == 1:
            return jax.random.uniform(key, (), dtype, -1.0, 1.0)[None]
        return jax.random.uniform(key, (self.n_swimmers,), dtype, -1.0, 1.0)

    def step(self, key: Array, state: Any, action: Array, params: Any) -> tuple[Any, StepInfo]:
        """One step, its noise drawn from ``key`` ([`noise`][jswim.env.base.Environment.noise]), then `advance`."""
        return self.advance(state, action, self.noise(key, state), params)

    def action_space(self, params: Any = None) -> Discrete:
        """The integer action codes."""
        return Discrete(self.n_actions)

    def roc_space(self, params: Any = None) -> Box:
        """Float ROC vectors ``(n_dof,)`` in [-1, 1]."""
        return Box(-1.0, 1.0, (self.n_dof,), jnp.result_type(float))

    def features(self, state: Any, params: Any) -> Array:
        """The observation as one flat float vector: the DOFs scaled to [-1, 1] (the default;
        worlds add what else a policy may read)."""
        raise NotImplementedError

    @property
    def n_features(self) -> int:
        """Length of [`features`][jswim.env.base.Environment.features]."""
        return self.n_dof

    # -- what the learners read, decided by the world ----------------------------------------

    def cells(self) -> Cells:
        """This world's discretiser for tabular learners (the default: each DOF's place on the
        K lattice, [`Cells`][jswim.env.discretiser.Cells])."""
        return Cells(self)

    def learner_advance(
        self, state: Any, action: Array, noise: Array, params: Any
    ) -> tuple[Any, StepInfo]:
        """The step the baselines (Q-learning, random, PPO) train on: `advance` (a world may
        step its learners in plainer arithmetic, as the paper's does)."""
        return self.advance(state, action, noise, params)

    def pose(self, state: Any, params: Any) -> tuple[Array, Array, Array]:
        """``(x, y, orientation)`` a learner's run records after each step: the swimmers' mean x,
        swimmer 1's y (its height above a wall) and orientation."""
        obs = self.observe(state, params)
        return jnp.mean(obs.position[:, 0]), obs.position[0, 1], obs.orientation[0]

    def termination(self, state: Any, params: Any) -> tuple[Array, Array]:
        """``(terminated, truncated)`` (bool scalars): the task's goal reached, and its step
        budget spent without reaching it (Gymnasium's two flags). Default ``(False, False)``:
        the paper's task (swim along x) never ends; a navigation world's does
        ([`NavigationWorld.termination`][jswim.env.navigation.NavigationWorld.termination])."""
        false = jnp.zeros((), bool)
        return false, false

    def judge_view(self, params: Any) -> tuple[Any, ...] | None:
        """The judge's view of this world: for each swimmer, the paper's swimmer (an
        [`EnvParams`][jswim.env.params.EnvParams] of the bulk fluid, its start that swimmer's)
        whose noiseless displacements the success criterion reads that swimmer's own moves with;
        ``None`` (the default): the criterion does not apply (its threshold is the paper
        swimmer's best stroke)."""
        return None

    def batch_params(self, params: Any, n: int) -> tuple[Any, Any]:
        """``params`` for ``n`` runs, and ``vmap``'s ``in_axes`` of them (hashable): a leaf with
        more axes than `default_params`' same leaf carries one value per run (axis 0), the
        others are shared (``None``).

        Raises
        ------
        ValueError
            When ``params`` does not have `default_params`' structure (a world whose params
            differ in structure overrides this).
        """
        ref = self.default_params
        axes = jax.tree.map(lambda a, r: 0 if jnp.ndim(a) > jnp.ndim(r) else None, params, ref)
        return params, axes


def scaled(values: Array, lo: Any, hi: Any) -> Array:
    """Values scaled from ``[lo, hi]`` to ``[-1, 1]``."""
    return 2.0 * (values - lo) / (hi - lo) - 1.0


def first_move(rocs: Array) -> tuple[Array, Array]:
    """``(dof, roc)`` of a ROC vector's first non-zero entry (DOF 0-based; ``(0, 0)`` if none)."""
    i = jnp.argmax(rocs != 0).astype(jnp.int32)
    return i, rocs[i]
