"""``SceneParams``: a scene, a sphere swimmer and the numerics, as a pytree for jit and vmap."""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any
from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np

from jswim.action_codes import check_roc_levels
from jswim.errors import ConfigError, check_zeta
from jswim.reals import is_real
from jswim.scenes.ranges import warn_out_of_range
from jswim.scenes.scene import Scene
from jswim.start_levels import parse_init
from jswim.swimmers.models import make_model

#: A step is refused when a sphere's surface would come closer than this to the wall, an
#: obstacle or another swimmer's sphere (units of a): the point-force model has no lubrication.
CONTACT_GAP = 0.1

#: Gauss-Legendre nodes per step (see `jswim.scenes.collocation`): order 12 in float64, and
#: order 8 in float32, whose quadrature error (~3e-9 of a step) is already below float32's rounding.
DEFAULT_NODES = 6
DEFAULT_NODES_FLOAT32 = 4


@functools.partial(
    jax.tree_util.register_dataclass,
    data_fields=["zeta", "centre0", "tilt0", "arms0", "obstacles"],
    meta_fields=["scene", "lo", "hi", "roc_levels", "nodes", "sweeps", "contact_gap"],
)
@dataclasses.dataclass(frozen=True)
class SceneParams:
    """Parameters of the scene environment ([`scene_params`][jswim.scenes.scene_parameters.scene_params] builds them).

    Attributes
    ----------
    zeta : float or Array
        Noise level >= 0 (the paper's ``(1 + zeta Y)`` on each step's displacement).
    centre0 : Array (S, 2)
        Start ``(x, z)`` of each swimmer's middle sphere.
    tilt0 : Array (S,)
        Start tilt of each swimmer, rad.
    arms0 : Array (S, 2)
        Start arm lengths ``(d1, d2)``.
    obstacles : Array (O, 3)
        Fixed spheres ``(x, z, radius)``.
    scene : Scene
        Static: the scene these were built from (``medium``, ``swimmers``).
    lo, hi : float
        Static arm limits (``d_min``, ``d_max``); ROC 1 moves an arm by ``hi - lo``.
    roc_levels : int
        Static K of integer action codes (`jswim.scenes.encode_scene_action`).
    nodes : int
        Static: Gauss-Legendre nodes per step.
    sweeps : int or None
        Static: Picard sweeps per step; ``None``: adaptive (until converged to the dtype).
    contact_gap : float
        Static: the surface gap below which a step is refused (`CONTACT_GAP`).
    """

    zeta: Any
    centre0: Any
    tilt0: Any
    arms0: Any
    obstacles: Any
    scene: Scene
    lo: float = 6.0
    hi: float = 10.0
    roc_levels: int = 1
    nodes: int = DEFAULT_NODES
    sweeps: int | None = None
    contact_gap: float = CONTACT_GAP

    def replace(self, **changes: Any) -> SceneParams:
        return dataclasses.replace(self, **changes)

    @property
    def n_swimmers(self) -> int:
        return self.scene.swimmers

    @property
    def n_dof(self) -> int:
        return 2

    @property
    def n_actions(self) -> int:
        """Integer action codes: ``swimmers x n_dof x (2K + 1)``."""
        return self.scene.swimmers * self.n_dof * (2 * self.roc_levels + 1)

    @property
    def wall(self) -> bool:
        return self.scene.medium == "wall"


def scene_params(
    swimmer: str,
    scene: Scene,
    *,
    zeta: float = 0.0,
    roc_levels: int = 1,
    dtype: Any = None,
    init: Sequence[int] | str | None = None,
    nodes: int | None = None,
    sweeps: int | None = None,
    contact_gap: float = CONTACT_GAP,
    **model_kwargs: Any,
) -> SceneParams:
    """Validated parameters of a scene with NG three-sphere swimmers.

    Parameters
    ----------
    swimmer : str
        ``"ng"`` (the three-sphere swimmer; ``d_min``/``d_max`` by keyword as in
        [`jswim.make_params`][jswim.env.params.make_params]).
    scene : Scene
        The scene (validated here).
    zeta : float
        Noise level >= 0.
    roc_levels : int
        K >= 1 for integer action codes (1: ROC in {-1, 0, 1}).
    dtype : dtype, optional
        Working dtype of states and solves (default: JAX's default float, float32 unless x64).
    init : levels, optional
        Start arms of every swimmer as in [`jswim.make_params`][jswim.env.params.make_params] (default both at ``d_max``).
    nodes : int, optional
        Gauss-Legendre nodes per step (default `DEFAULT_NODES`, 6; in float32
        `DEFAULT_NODES_FLOAT32`, 4).
    sweeps : int, optional
        Picard sweeps per step. Default: 1 where the motion does not depend on the pose (one
        swimmer in the unbounded fluid, or bulk), else adaptive: sweeps until the estimated error
        is below the dtype's rounding ([`jswim.scenes.scene_stepping.picard_tolerance`][jswim.scenes.scene_stepping.picard_tolerance]; 3 to 16
        sweeps, more near a wall or a neighbour); an integer fixes the count.
    contact_gap : float
        Surface gap (units of a) below which a step is refused.

    Raises
    ------
    ConfigError (a ValueError)
        Bad swimmer, scene, zeta or start (spheres overlapping or touching the wall at the start).
    """
    centre, tilt, arms, obstacles = check_start(swimmer, scene, init, contact_gap, **model_kwargs)
    model = make_model("ng", **model_kwargs)
    warn_out_of_range(swimmer, scene, d_max=model.hi)
    z = check_zeta(zeta)
    dtype = jnp.result_type(float) if dtype is None else jnp.dtype(dtype)
    if nodes is None:
        nodes = DEFAULT_NODES_FLOAT32 if dtype.itemsize <= 4 else DEFAULT_NODES
    nodes, sweeps = (
        _plain_int(nodes),
        _plain_int(sweeps),
    )  # a NumPy integer is the int it holds (static, hashed)
    if isinstance(nodes, bool) or not isinstance(nodes, int) or not 1 <= nodes <= 32:
        raise ConfigError(f"nodes must be an integer in 1..32, got {nodes!r}")
    pose_free = scene.medium == "bulk" or (
        scene.medium == "free" and scene.swimmers == 1 and not scene.obstacles
    )
    if sweeps is None and pose_free:
        sweeps = 1
    if sweeps is not None and (
        isinstance(sweeps, bool) or not isinstance(sweeps, int) or not 1 <= sweeps <= 64
    ):
        raise ConfigError(f"sweeps must be an integer in 1..64, got {sweeps!r}")
    _check_resolution(scene, centre, obstacles, np.dtype(dtype), float(model.hi))
    as_dtype = functools.partial(jnp.asarray, dtype=dtype)
    return SceneParams(
        zeta=z,
        centre0=as_dtype(centre),
        tilt0=as_dtype(tilt),
        arms0=as_dtype(arms),
        obstacles=as_dtype(obstacles),
        scene=scene,
        lo=float(model.lo),
        hi=float(model.hi),
        roc_levels=check_roc_levels(roc_levels, "roc_levels"),
        nodes=nodes,
        sweeps=sweeps,
        contact_gap=float(contact_gap),
    )


def batch_starts(
    params: SceneParams, *, height: Any = None, tilt: Any = None, separation: Any = None
) -> SceneParams:
    """``params`` with a leading batch axis of start poses: one compiled scene, many starts.

    ``height``, ``tilt`` and ``separation`` are 1-D arrays of one length ``B`` (or None: the
    scene's own value); the result's ``centre0`` is ``(B, S, 2)`` and ``tilt0`` ``(B, S)``, the other
    leaves are shared. ``params.scene`` (static) stays the template; the starts are not validated
    again beyond finiteness. Run with [`jswim.env.scene_rollout_batch`][jswim.env.scene_rollouts.scene_rollout_batch].
    """
    sc = params.scene
    vals = [
        np.asarray(v, np.float64).reshape(-1) for v in (height, tilt, separation) if v is not None
    ]
    if not vals:
        raise ConfigError("batch_starts needs at least one of height, tilt, separation")
    b = len(vals[0])
    if any(len(v) != b for v in vals) or not all(np.all(np.isfinite(v)) for v in vals):
        raise ConfigError(
            "batch_starts: height, tilt and separation must be finite and of one length"
        )
    h = np.broadcast_to(np.asarray(sc.height if height is None else height, np.float64), (b,))
    t = np.broadcast_to(np.asarray(sc.tilt if tilt is None else tilt, np.float64), (b,))
    d = np.broadcast_to(
        np.asarray(sc.separation if separation is None else separation, np.float64), (b,)
    )
    s = sc.swimmers
    centre = (
        sc.start_offsets()[None] * d[:, None, None] + np.stack([np.zeros(b), h], -1)[:, None, :]
    )
    dtype = params.arms0.dtype
    return params.replace(
        centre0=jnp.asarray(centre, dtype), tilt0=jnp.asarray(np.repeat(t[:, None], s, 1), dtype)
    )


def check_start(
    swimmer: str,
    scene: Scene,
    init: Sequence[int] | str | None = None,
    contact_gap: float = CONTACT_GAP,
    **model_kwargs: Any,
) -> tuple[np.ndarray, ...]:
    """The start of ``scene`` (the one check of it, NumPy, float64, no JAX work): each swimmer's
    middle sphere ``(S, 2)``, tilt ``(S,)``, arms ``(S, 2)`` and the obstacles ``(O, 3)``, if no
    sphere starts closer than ``contact_gap`` to the wall, an obstacle or another swimmer's.

    [`scene_params`][jswim.scenes.scene_parameters.scene_params] calls it; [`jswim.studies.StudyOptions`][jswim.studies.options.StudyOptions] too, so a study's
    ``--separations`` that would overlap its swimmers is refused before anything runs.

    Raises
    ------
    ConfigError
        A bad scene, swimmer or start, in one line (an overlap names the separation it needs).
    """
    if not isinstance(scene, Scene):
        raise ConfigError(f"scene must be a jswim.scenes.Scene, got {type(scene).__name__}")
    scene.validate()
    if not isinstance(swimmer, str) or swimmer.lower() != "ng":
        raise ConfigError(
            f"scenes hold NG three-sphere swimmers only (swimmer='ng'), got {swimmer!r}"
        )
    model = make_model("ng", **model_kwargs)
    if not (is_real(contact_gap) and math.isfinite(contact_gap) and contact_gap >= 0):
        raise ConfigError(f"contact_gap must be a number >= 0, got {contact_gap!r}")
    levels = np.asarray(parse_init(init, 2), np.float64)
    if np.any(levels < 0):
        raise ConfigError("init='random' is not offered for scenes; give levels like (1, 1)")
    s = scene.swimmers
    arms = np.broadcast_to(model.lo + (model.hi - model.lo) * levels, (s, 2))
    centre = scene.start_offsets() * scene.separation + np.array([0.0, scene.height])
    tilt = np.full(s, scene.tilt)
    obstacles = np.asarray(scene.obstacles, np.float64).reshape(-1, 3)
    _check_start(scene, centre, tilt, arms, obstacles, float(contact_gap))
    return centre, tilt, arms, obstacles


def _plain_int(v: Any) -> Any:
    return int(v) if isinstance(v, np.integer) else v


#: Coarsest spacing (a) the working dtype may have at a swimmer's start x: a swimmer far from
#: x = 0 (swimmer 2 at D) moves in steps of its position's rounding, so float32 at D = 1e5 a
#: rounds its displacement per cycle to 0.1719 (0.1721) and at 1e7 a it does not move at all.
POSITION_RESOLUTION = 1e-4


def _check_resolution(
    scene: Scene, centre: np.ndarray, obstacles: np.ndarray, dtype: np.dtype, reach: float
) -> None:
    """One-line error if the start does not fit the working dtype: a coordinate that overflows it,
    or a swimmer so far from x = 0 that its moves are lost to rounding (`POSITION_RESOLUTION`)."""
    with np.errstate(over="ignore"):
        fits = np.all(np.isfinite(centre.astype(dtype))) and np.all(
            np.isfinite(obstacles.astype(dtype))
        )
    if not fits:
        raise ConfigError(
            f"the scene's heights, separation or obstacles overflow {dtype.name}: give finite, smaller lengths"
        )
    far = float(np.abs(centre[:, 0]).max()) + 2 * reach  # the farthest sphere's x at the start
    step = float(np.spacing(np.asarray(far, dtype)))
    if step > POSITION_RESOLUTION:
        # spacing(x) = eps 2^floor(log2 x): fine enough below the next power of two
        limit = (
            2.0 ** (math.floor(math.log2(POSITION_RESOLUTION / float(np.finfo(dtype).eps))) + 1)
            - 2 * reach
        )
        more = (
            ', or float64 from Python (scene_params(..., dtype="float64") with jax_enable_x64)'
            if dtype.itemsize < 8
            else ""
        )
        raise ConfigError(
            f"separation {scene.separation:g} a is too far for {dtype.name} positions (they are rounded "
            f"to {step:.2g} a there, more than {POSITION_RESOLUTION:g} a): use a separation below "
            f"{limit:g} a{more}"
        )


def _check_start(
    scene: Scene,
    centre: np.ndarray,
    tilt: np.ndarray,
    arms: np.ndarray,
    obstacles: np.ndarray,
    gap: float,
) -> None:
    """One-line error if the start already has a contact (NumPy, float64)."""
    if scene.medium == "bulk":
        return
    q = np.concatenate([np.zeros((len(arms), 1)), np.cumsum(arms, -1)], -1)
    q = q - q[:, 1:2]
    e = np.stack([np.cos(tilt), np.sin(tilt)], -1)
    pos = centre[:, None, :] + q[..., None] * e[:, None, :]  # (S, 3, 2)
    if scene.medium == "wall":
        low = float(pos[..., 1].min()) - 1.0
        if low < gap:
            raise ConfigError(
                f"the swimmer starts with a sphere {low:.3g} a from the wall (needs >= {gap}); raise height or lower tilt"
            )
    for o in obstacles:
        g = float(np.min(np.hypot(*(pos - o[:2]).transpose(2, 0, 1))) - 1.0 - o[2])
        if g < gap:
            raise ConfigError(
                f"obstacle {tuple(o.tolist())} is {g:.3g} a from a swimmer sphere at the start (needs >= {gap})"
            )
    if len(pos) >= 2:
        d = pos[:, None, :, None, :] - pos[None, :, None, :, :]  # (S, S, n, n, 2)
        dist = np.hypot(d[..., 0], d[..., 1]).min(axis=(2, 3)) + np.diag(np.full(len(pos), np.inf))
        g = float(dist.min()) - 2.0
        if scene.formation == "line":  # each one wholly behind the next, not interleaved
            g = min(g, float(np.min(pos[1:, :, 0].min(-1) - pos[:-1, :, 0].max(-1))) - 2.0)
        if g < gap:  # untilted, g grows one for one with the separation: the bound
            least = f" above {scene.separation + gap - g:.4g}" if scene.tilt == 0 else ""
            raise ConfigError(
                f"the swimmers' spheres start {g:.3g} a apart (needs >= {gap}); raise separation{least}"
            )
