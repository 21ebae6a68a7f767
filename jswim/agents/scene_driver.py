"""The LLM driver's scene side (issue 19): a batched scene state with the interface of the bulk
driver's group, and the prompt text of a scene run.

:class:`jswim.agents.llm.LLMDriver` keeps one group per swimmer model; a run with a scene
(``LLMRunSpec.scene``) joins a :class:`SceneGroup` of the runs with the same scene, noise level
and ROC lattice instead. Everything else (prompt, call, parse, retries, journal, transcripts) is
the same code path as the paper's.
"""

from __future__ import annotations

import asyncio
from typing import Any, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from jswim import env

from jswim.judging import lattice
from jswim.agents import scene_env
from jswim.agents.defaults import dof_decimals
from jswim.agents.step_batcher import StepBatcher
from jswim.agents.variants import NO_OP, LLMRunSpec
from jswim.prompt import PromptTemplate, SceneView, SwimmerText, scene_template
from jswim.swimmers.models import make_model


def view(scene: Any, own: int = 0) -> SceneView:
    """What the prompt shows of ``scene`` (:class:`jswim.prompt.SceneView`); ``own`` 1 or 2: the
    prompt of that swimmer of a pair alone (``--pair-prompt each``)."""
    return SceneView(scene_env.n_swimmers(scene), scene_env.has_wall(scene),
                     float(scene.separation) if scene_env.n_swimmers(scene) > 1 else 0.0, own)


def scene_text(spec: LLMRunSpec, template: PromptTemplate, rocs: tuple[int, ...] | None = None,
               own: int = 0) -> tuple[SwimmerText, PromptTemplate]:
    """The joint swimmer text (two arms per swimmer, the NG ranges) and the template of a scene run
    (:func:`jswim.prompt.scene_template`: the default grows the scene's fields; a user's is kept);
    ``own`` 1 or 2: swimmer ``own``'s text alone (its two arms; :mod:`jswim.agents.pair_prompt`)."""
    scene = scene_env.from_json(spec.scene)
    model = make_model(spec.swimmer, **dict(spec.swimmer_options))
    k = spec.roc_levels
    n = scene_env.ARMS * (1 if own else scene_env.n_swimmers(scene))
    v = view(scene, own)
    text = SwimmerText(n, model.lo, model.hi, dof_decimals(model, k),
                       tuple(rocs) if rocs is not None else tuple(range(-k, k + 1)), k, scene=v)
    return text, scene_template(v, template)


def _step(params: Any, roc_levels: int):
    def one(state, code, key):
        return scene_env.step(params, state, code, key, roc_levels)

    @jax.jit
    def advance(base_keys, t, states, codes, mask):
        keys = jax.vmap(jax.random.fold_in)(base_keys, t)
        new, obs = jax.vmap(one)(states, codes, keys)
        keep = lambda a, b: jnp.where(mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, b)  # noqa: E731
        return jax.tree.map(keep, new, states), obs

    return advance


class SceneGroup(StepBatcher):
    """Runs sharing one scene, noise level and ROC lattice: one batched scene state, stepped like
    :class:`jswim.agents.llm._Group` (actions handed in during one event-loop turn go together).

    Positions are displacements from each swimmer's start (X starts at 0 as in the bulk
    environment); ``x`` is their mean, whose progress in the target direction is the reward.
    """

    def __init__(self, members: list[int], specs: Sequence[LLMRunSpec]) -> None:
        self.members = members
        s0 = specs[0]
        self.scene = scene_env.from_json(s0.scene)
        self.roc_levels = int(s0.roc_levels)
        self.params = scene_env.scene_params(s0.swimmer, self.scene, zeta=s0.zeta, roc_levels=self.roc_levels,
                                             init=scene_env.start_levels(s0.init))
        self.direction = np.array([s.direction for s in specs], np.float64)
        keys = jnp.stack([env.seed_key(s.seed) for s in specs])
        self.step_keys = jax.vmap(jax.random.split)(keys)[:, 1]
        self.states, obs = scene_env.start(self.params, len(members))
        o = scene_env.as_numpy(obs)
        self.xs0 = o["xs"]
        self.dofs = o["dofs"]
        self.z0, self.tilt0 = o["z"], o["tilt"]
        model = make_model(s0.swimmer, **dict(s0.swimmer_options))
        self.levels0 = np.rint((self.dofs - model.lo) / (model.hi - model.lo)).astype(np.int64)
        self.t = np.zeros(len(members), np.int32)
        self._xs = np.zeros_like(self.xs0)  # each member's displacements after its last step
        self._advance = _step(self.params, self.roc_levels)
        self._noop = lattice.encode(*NO_OP, self.roc_levels)
        self._pending: dict[int, tuple[int, asyncio.Future]] = {}
        self.n_steps = 0

    def start_view(self, pos: int) -> dict[str, Any]:
        """Member ``pos``'s positions, heights and tilts before its first step."""
        return {"xs": np.zeros(self.xs0.shape[1]), "heights": self.z0[pos], "tilts": self.tilt0[pos]}

    def _step(self, codes: np.ndarray, mask: np.ndarray) -> Any:
        self.states, obs = self._advance(self.step_keys, jnp.asarray(self.t), self.states, codes, mask)
        o = scene_env.as_numpy(obs)
        self.t = self.t + mask.astype(np.int32)
        xs = o["xs"] - self.xs0
        old = self._xs
        self._xs = np.where(mask[:, None], xs, old)

        def outputs(pos: int) -> dict[str, Any]:
            x = float(np.mean(xs[pos]))
            return {
                "x": x, "progress": self.direction[pos] * (x - float(np.mean(old[pos]))), "stuck": bool(o["stuck"][pos]),
                "dofs": o["dofs"][pos], "y": float(o["z"][pos, 0]), "orientation": float(o["tilt"][pos, 0]),
                "xs": xs[pos], "heights": o["z"][pos], "tilts": o["tilt"][pos], "contact": bool(o["contact"][pos]),
            }

        return outputs
