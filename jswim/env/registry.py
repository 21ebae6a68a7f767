"""``make``: a world and its params from a swimmer and an optional scene (the protocol's door);
``register_world``: a new world by name, which ``make``, the studies and the pictures then take."""

from __future__ import annotations

from typing import Any
from collections.abc import Callable, Sequence

from jswim.env.base import Environment
from jswim.env.params import EnvParams, make_params, parse_direction
from jswim.env.scene_world import SceneTask, SceneWorld
from jswim.env.swimmer_world import SwimmerWorld
from jswim.env.flows import Uniform
from jswim.errors import ConfigError
from jswim.scenes import purcell_wall
from jswim.scenes.scene_parameters import scene_params
from jswim.scenes.scene import Scene
from jswim.swimmers.models import SWIMMERS, SwimmerModel

#: Worlds added by name ([`register_world`][jswim.env.registry.register_world]): name -> factory.
_REGISTERED: dict[str, Callable[..., tuple[Environment, Any]]] = {}


def register_world(name: str, factory: Callable[..., tuple[Environment, Any]]) -> None:
    """Add a world by name: ``jswim.make(name, scene, **options)`` then returns ``factory(scene,
    zeta=, direction=, init=, **options)`` (``scene`` a [`jswim.scenes.Scene`][jswim.scenes.scene.Scene] or ``None``,
    ``direction`` +1 or -1, ``init`` start levels or ``None``; only the options asked for), an
    [`Environment`][jswim.env.base.Environment] and its params (a NamedTuple or dataclass with a
    ``direction`` field), and a study whose runs name it as their swimmer runs it. The factory
    raises a one-line [`ConfigError`][jswim.errors.ConfigError] for a scene or option it does not take; registering a
    name again replaces its factory.

    Raises
    ------
    ConfigError
        For an empty name, one of the paper's swimmers, or a factory that is not callable.
    """
    if not isinstance(name, str) or not name or name.lower() in SWIMMERS or not callable(factory):
        raise ConfigError(
            f"register_world needs a new name (not {', '.join(SWIMMERS)}) and a callable factory, "
            f"got {name!r}"
        )
    _REGISTERED[name] = factory


def registered_worlds() -> tuple[str, ...]:
    """The names [`register_world`][jswim.env.registry.register_world] added, in order."""
    return tuple(_REGISTERED)


def as_scene(scene: Any) -> Scene:
    """``scene`` validated: a [`jswim.scenes.Scene`][jswim.scenes.scene.Scene] or its dict ([`Scene.from_dict`][jswim.scenes.scene.Scene.from_dict])."""
    if isinstance(scene, dict):
        return Scene.from_dict(scene)
    if not isinstance(scene, Scene):
        raise ConfigError(f"scene must be a jswim.scenes.Scene, got {type(scene).__name__}")
    return scene.validate()


def is_plain_bulk(scene: Any) -> bool:
    """Whether ``scene`` is the paper's world: one untilted swimmer in the bulk medium."""
    scene = as_scene(scene)
    return scene.medium == "bulk" and scene.swimmers == 1 and scene.tilt == 0.0


def make(
    swimmer: str | SwimmerModel = "purcell",
    scene: Scene | dict | None = None,
    *,
    zeta: float = 0.0,
    direction: int | str = 1,
    init: Sequence[int] | str | None = None,
    roc_levels: int = 1,
    diagonal: bool = False,
    dtype: Any = None,
    target: Any = None,
    flow: Any = None,
    **kwargs: Any,
) -> tuple[Environment, Any]:
    """A world and its params.

    Parameters
    ----------
    swimmer : str or SwimmerModel
        ``"purcell"``, ``"ng"``, ``"nlink"``, ``"nsphere"``, or a world of [`register_world`][jswim.env.registry.register_world]
        (its factory gets the scene, zeta, direction, init and the keywords) (scenes: ``"ng"``; ``"purcell"`` above a
        wall, [`jswim.scenes.purcell_wall`][jswim.scenes.purcell_wall]: the paper's world with wall-corrected drag, its
        plane ``scene.height`` link lengths up, ``link_radius`` by keyword); model options
        (``d_max``, ``d_min``, ``n_links``, ...) by keyword.
    scene : Scene or dict, optional
        ``None``, or one untilted swimmer in the ``"bulk"`` medium: the paper's world
        ([`SwimmerWorld`][jswim.env.swimmer_world.SwimmerWorld], params [`jswim.env.EnvParams`][jswim.env.params.EnvParams]).
        Anything else: a [`SceneWorld`][jswim.env.scene_world.SceneWorld] (params
        [`SceneTask`][jswim.env.scene_world.SceneTask]).
    zeta, direction, init, roc_levels
        As in [`jswim.env.make_params`][jswim.env.params.make_params] (every world has a target direction).
    diagonal : bool
        The paper's world only: ROC vectors may move several DOFs at once.
    dtype : dtype, optional
        Scenes only: the working dtype of states and solves (default JAX's default float). The
        paper's world follows JAX's default float (its positions are drift-free pairs).
    target : FixedTarget, Waypoints or MovingTarget, optional
        A navigation task ([`jswim.env.targets`][jswim.env.targets]): the world becomes a
        [`NavigationWorld`][jswim.env.navigation.NavigationWorld] around the swimmer's (params
        [`NavParams`][jswim.env.navigation.NavParams]); with it the keywords ``bearing_bins``
        and ``lattice`` ([`navigation_world`][jswim.env.navigation.navigation_world]). Planar
        swimmers with ``roc_levels >= 2``, in the bulk or in a plane above a wall; docs/navigation.md.
    flow : Flow, optional
        A background flow ([`jswim.env.flows`][jswim.env.flows]) in the bulk: any flow for a
        planar swimmer, with or without a target; a stream along its line,
        ``Uniform((ux, 0))``, for a swimmer that moves on a line; above a wall, Purcell's plane
        only, the wall's shear there, a `Uniform` stream (`_check_wall_flow`); ``None`` (the default) is still fluid, every number as
        before (docs/physics.md, Background flows).
    **kwargs
        More options of [`jswim.env.make_params`][jswim.env.params.make_params] or [`jswim.scenes.scene_params`][jswim.scenes.scene_parameters.scene_params]
        (``nodes``, ``sweeps``, ``contact_gap``).

    Returns
    -------
    env : Environment
        The world (static, hashable: jit and vmap take it as a static argument).
    params : EnvParams, SceneParams or NavParams
        Its parameters (a pytree of arrays; `Environment.batch_params` stacks them along a
        leading axis).

    Raises
    ------
    ConfigError
        Any invalid value (one line).

    Examples
    --------
    >>> env, params = make("purcell", direction="-x")
    >>> env.n_dof, env.n_actions
    (2, 6)
    >>> env, params = make("ng", Scene(medium="wall", height=5.0, swimmers=2))
    >>> env.n_swimmers, env.n_dof
    (2, 4)
    >>> env, params = make("purcell", roc_levels=2, target=FixedTarget(3.0, bearing=90))
    >>> env.n_features
    5
    """
    options = {
        "zeta": zeta,
        "direction": direction,
        "init": init,
        "roc_levels": roc_levels,
        "diagonal": diagonal,
        "dtype": dtype,
    }
    if flow is not None:
        if scene is not None and not is_plain_bulk(scene):
            _check_wall_flow(swimmer, as_scene(scene), flow)
        if isinstance(swimmer, str) and swimmer in _REGISTERED:
            raise ConfigError(f"the registered world {swimmer!r} takes no background flow")
        kwargs = {**kwargs, "flow": flow}
    if target is not None:
        return _navigation_world(swimmer, scene, target, options, kwargs)
    if isinstance(swimmer, str) and swimmer in _REGISTERED:
        return _registered_world(swimmer, scene, options, kwargs)
    if scene is not None and purcell_wall.is_purcell(swimmer) and not is_plain_bulk(scene):
        # Purcell's swimmer above a wall: the paper's planar world with wall-corrected drag
        kept = {"flow": kwargs.pop("flow")} if "flow" in kwargs else {}
        swimmer, scene, kwargs = purcell_wall.model(as_scene(scene), **kwargs), None, kept
    if scene is None or is_plain_bulk(scene):
        return _paper_world(swimmer, options, kwargs)
    return _scene_world(swimmer, as_scene(scene), options, kwargs)


def _check_wall_flow(swimmer: Any, scene: Scene, flow: Any) -> None:
    """Refuse a flow where a scene cannot take it, in one line.

    Above a wall the flow that keeps no-slip is the wall's own shear, ``(rate z, 0)``. Purcell's
    swimmer swims in a plane at height ``h`` parallel to the wall, where that flow is a uniform
    stream ``rate h``: a `Uniform` flow, exact in both wall models (the drag of every element is
    against its velocity relative to the undisturbed flow, which no-slip leaves unchanged). The
    sphere scenes' steps last as long as their arm moves (only the path matters in still fluid),
    which a flow, needing the step's time, cannot use.
    """
    if purcell_wall.is_purcell(swimmer) and scene.medium != "wall":
        return  # not a scene Purcell's swimmer swims in: make's own refusal says why
    if not purcell_wall.is_purcell(swimmer):
        raise ConfigError(
            "a background flow is offered in the bulk and in Purcell's plane above a wall so far, "
            f"not in a {scene.medium!r} sphere scene (its steps have no fixed duration)"
        )
    if not isinstance(flow, Uniform):
        raise ConfigError(
            "above a wall the flow that keeps no-slip is the wall's shear (rate z, 0): in "
            f"Purcell's plane at height h a uniform stream, Uniform((rate * h, 0)), not {flow!r}"
        )


def _navigation_world(
    swimmer: Any, scene: Any, target: Any, options: dict[str, Any], kwargs: dict[str, Any]
) -> tuple[Environment, Any]:
    """``make(..., target=target)``: the world of the rest, wrapped in a navigation task."""
    from jswim.env.navigation import navigation_world  # lazy: the task's own module

    nav = {k: kwargs.pop(k) for k in ("bearing_bins", "lattice") if k in kwargs}
    if parse_direction(options["direction"]) != 1:
        raise ConfigError(
            "a navigation world swims to its target: direction does not apply (leave it out)"
        )
    if isinstance(swimmer, str) and swimmer in _REGISTERED:
        raise ConfigError(
            f"navigation wraps the paper's planar swimmers, not the registered world {swimmer!r}"
        )
    world, params = make(swimmer, scene, **options, **kwargs)
    return navigation_world(world, params, target, **nav)


def _registered_world(
    name: str, scene: Any, options: dict[str, Any], kwargs: dict[str, Any]
) -> tuple[Environment, Any]:
    """A world of [`register_world`][jswim.env.registry.register_world]: its factory gets the
    scene, zeta, direction, init, only the other options given (it refuses what it lacks), and
    the keywords."""
    given = {
        **({"roc_levels": options["roc_levels"]} if options["roc_levels"] != 1 else {}),
        **({"diagonal": True} if options["diagonal"] else {}),
        **({"dtype": options["dtype"]} if options["dtype"] is not None else {}),
    }
    return _REGISTERED[name](
        None if scene is None else as_scene(scene),
        zeta=options["zeta"],
        direction=parse_direction(options["direction"]),
        init=options["init"],
        **given,
        **kwargs,
    )


def _paper_world(
    swimmer: str | SwimmerModel, options: dict[str, Any], kwargs: dict[str, Any]
) -> tuple[SwimmerWorld, EnvParams]:
    """The paper's world (a plain bulk scene, or Purcell's wall model) and its ``EnvParams``."""
    options = dict(options)
    if options.pop("dtype") is not None:
        raise ConfigError("dtype is a scene option; the paper's world follows JAX's default float")
    params = make_params(swimmer, **options, **kwargs)
    return SwimmerWorld(params.model, params.roc_levels, params.diagonal), params


def _scene_world(
    swimmer: Any, scene: Scene, options: dict[str, Any], kwargs: dict[str, Any]
) -> tuple[SceneWorld, SceneTask]:
    """A scene's world (walls, obstacles, pairs, schools) and its ``SceneTask``."""
    options = dict(options)
    if options.pop("diagonal"):
        raise ConfigError("diagonal strokes are not offered in scenes (one arm moves per step)")
    direction = float(parse_direction(options.pop("direction")))
    sp = scene_params(swimmer, scene, **options, **kwargs)
    return SceneWorld(scene, sp.roc_levels), SceneTask(sp, direction)
