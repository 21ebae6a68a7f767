"""A new world needs no agent code: a toy world written against the protocol alone (jswim.env.base,
here with any number of swimmers) is driven by the LLM agent's one step group against the fake
server, its prompt, records and rows coming from the world's own sizes and observation.

The toy's physics is the area rule of tests/env/test_toy_world.py, per swimmer: a step moves
swimmer s by ``(f1 df2 - f2 df1) / 2`` at the step's mid-shape (``f`` its two DOFs' places in
[0, 1]), so the counter-clockwise square from (1, 1) nets exactly +1 per cycle (0.5 at its first
and last moves). The DOFs are shown as NG's arms, ``6 + 4 f``, so the run's text is NG's.
"""

import dataclasses
import re
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import pytest

from jswim.agents.llm import run_batch
from jswim.agents.variants import LLMAgentConfig, LLMRunSpec
from jswim.env.base import Environment, Observation, StepInfo
from jswim.llm import ClientSettings
from tests.fakeserver import FakeServer


class ToyState(NamedTuple):
    frac: jax.Array  # (S, 2)
    x: jax.Array  # (S,)


class ToyParams(NamedTuple):
    zeta: Any = 0.0
    direction: Any = 1.0


@dataclasses.dataclass(frozen=True)
class SchoolToy(Environment):
    swimmers: int = 1

    @property
    def n_swimmers(self) -> int:
        return self.swimmers

    @property
    def n_dof(self) -> int:
        return 2 * self.swimmers

    default_params = ToyParams()

    def reset(self, key, params):
        f = jnp.result_type(float)
        return ToyState(jnp.ones((self.swimmers, 2), f), jnp.zeros(self.swimmers, f))

    def advance(self, state, action, noise, params):
        dof, roc = (
            action // 3,
            (action % 3 - 1).astype(state.x.dtype),
        )  # the protocol's codes, K = 1
        f1 = jnp.clip(
            state.frac + roc * (jnp.arange(self.n_dof) == dof).reshape(self.swimmers, 2), 0.0, 1.0
        )
        mid, d = (state.frac + f1) / 2, f1 - state.frac
        dx = 0.5 * (mid[:, 0] * d[:, 1] - mid[:, 1] * d[:, 0]) * (1.0 + params.zeta * noise)
        moved = jnp.any(d != 0)
        info = StepInfo(
            jnp.stack([dx, 0.0 * dx], -1),
            params.direction * jnp.mean(dx),
            (roc != 0) & ~moved,
            moved,
            jnp.zeros((), bool),
            jnp.asarray(jnp.inf, dx.dtype),
        )
        return ToyState(f1, state.x + dx), info

    def observe(self, state, params):
        position = jnp.stack([state.x, 0.0 * state.x], -1)
        return Observation(
            6.0 + 4.0 * state.frac.reshape(-1),
            position,
            jnp.zeros(self.swimmers, state.x.dtype),
            position[:, 1],
        )


#: Swimmer 1's counter-clockwise square on NG's arms: the next move from each corner.
SQUARE = {
    ("10", "10"): "[1, -1]",
    ("6", "10"): "[2, -1]",
    ("6", "6"): "[1, 1]",
    ("10", "6"): "[2, 1]",
}


def square_reply(body):
    """Swimmer 1's next square move from its shape now (the last record's, or the start (10, 10))."""
    prompt = body["messages"][-1]["content"]
    after = re.findall(r"-> \(([\d, ]+)\)", prompt)
    shape = tuple(after[-1].split(", ")[:2]) if after else ("10", "10")
    return SQUARE[shape]


@pytest.mark.slow  # compiles the group's start and step for two worlds (~9 s under load)
def test_a_toy_world_of_any_size_runs_through_the_llm_agent(float32):
    specs = [
        LLMRunSpec("ng", n_steps=12, seed=1, run_id="alone"),
        LLMRunSpec("ng", n_steps=12, seed=2, run_id="school"),
    ]
    worlds = {"alone": SchoolToy(1), "school": SchoolToy(3)}
    with FakeServer(reply=square_reply) as srv:
        settings = ClientSettings(base_url=srv.url, model="fake", timeout_s=120.0)
        alone, school = run_batch(
            specs,
            settings,
            LLMAgentConfig(),
            worlds=lambda s: (worlds[s.run_id], ToyParams(direction=float(s.direction))),
        )
    # Three exact square cycles, +1 each (0.5 at the first and last move of a cycle).
    assert alone.status == school.status == "done"
    assert alone.x[:4] == [0.5, 0.5, 0.5, 1.0] and alone.x[-1] == 3.0 and sum(alone.progress) == 3.0
    assert alone.actions[:4] == [
        0,
        3,
        2,
        5,
    ]  # the protocol's codes of [1, -1], [2, -1], [1, 1], [2, 1]
    # One swimmer and no wall: the paper's prompt and row, nothing added.
    steps = [t for t in alone.transcript if t["type"] == "step"]
    assert "X 4500 -> 5000" in steps[-1]["prompt"] and "X1" not in steps[-1]["prompt"]
    assert "xs" not in alone.as_row() and alone.levels0 == [1, 1]
    # Three swimmers: joint DOFs D1..D6, each swimmer's X in the records, the mean as the reward's X.
    first, last = [t["prompt"] for t in school.transcript if t["type"] == "step"][::11]
    assert "D1, D2, D3, D4, D5 and D6" in first and "up to D6 of swimmer 3" in first
    assert (
        "swimmer 2 at (0, 0) and swimmer 3 at (0, 0)" in first
    )  # the toy stacks them at the origin
    assert "[changed DOF, ROC], the changed DOF 1, 2, 3, 4, 5 or 6" in first
    assert "X1 4500 -> 5000, X2 2500 -> 2500, X3 2500 -> 2500, stuck no" in last
    assert school.xs[-1] == [3.0, 0.0, 0.0] and school.x[-1] == pytest.approx(1.0)
    assert school.heights[-1] == [0.0, 0.0, 0.0] and school.actions == alone.actions
    row = school.as_row()
    assert row["xs"] == school.xs and row["pair_prompt"] == "joint" and school.levels0 == [1] * 6
