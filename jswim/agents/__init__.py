"""The agents: one entry point each, on any world of the protocol.

The learners and drivers are modules, loaded on first use so that ``import jswim.agents`` stays
light (JAX loads with the first of them):

- `jswim.agents.llm`: the LLM driver (prompt -> client -> parse -> step);
- `jswim.agents.qlearning`: tabular Q-learning (``qlearning.train``);
- `jswim.agents.ppo`: PPO (``ppo.train``);
- `jswim.agents.random_policy`: the random policy (``random_policy.run``);
- `jswim.agents.strokes`: fixed strokes (``strokes.play``);
- `jswim.agents.steering`: the navigation controller (``steering.run``);
- `jswim.agents.zermelo`: Zermelo's time-optimal path of a point through a flow
  (``zermelo.zermelo``);
- `jswim.agents.optimal`: the swimmer's own optimum (``optimal.solve``), the navigation study's
  yardstick;
- `jswim.agents.mpc`: the model-predictive agent (``mpc.run``).

The other modules (``defaults``, ``fidelity``, ``memory``, ``pair_prompt``, ``ppo_judge``,
``protocol``, ``rewards``, ``step_batcher``, ``variants``, ``world_view``) are their parts.
"""

from __future__ import annotations

from jswim._exports import lazy_exports

__all__ = [
    "llm",
    "mpc",
    "optimal",
    "ppo",
    "qlearning",
    "random_policy",
    "steering",
    "strokes",
    "zermelo",
]

_PARTS = (
    "cost_to_go",
    "defaults",
    "fidelity",
    "memory",
    "pair_prompt",
    "ppo_judge",
    "protocol",
    "rewards",
    "step_batcher",
    "variants",
    "world_view",
)

__getattr__, __dir__ = lazy_exports(__name__, {}, (*__all__, *_PARTS))
