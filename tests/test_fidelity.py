"""The paper's protocol by default, element by element (values from ../shared/fidelity.md and the
paper, never from jswim's own output): starts, and the end-to-end request log of `jswim swim`."""

from __future__ import annotations

import math

import jax
import numpy as np
import pytest

from jswim import env
from jswim.studies.grids import initial
from jswim.swimmers import nlink


@pytest.mark.parametrize("swimmer, levels, values", [
    ("purcell", (1, 1), (math.pi / 3, math.pi / 3)),  # (pi/3, pi/3)
    ("ng", (1, 0), (10.0, 6.0)),  # NG (10, 6)
    ("nsphere", (0, 1, 1), (6.0, 10.0, 10.0)),  # four-sphere (6, 10, 10)
    ("nlink", (1, 1, 1), (2 * math.pi / 9,) * 3),  # four-link: every hinge at +2pi/9
])
def test_paper_start_is_the_authors_start(swimmer, levels, values):
    assert initial("paper", 0, swimmer) == levels
    params = env.make_params(swimmer, init=levels)
    state = env.reset(jax.random.PRNGKey(0), params)
    np.testing.assert_allclose(np.asarray(env.dof_values(state, params)), values, rtol=1e-6)


def test_start_orientation_middle_link_along_x_and_four_link_chain_symmetric_about_x():
    # Purcell: the middle link along +x.
    p = env.make_params("purcell", init=(1, 1))
    assert float(env.reset(jax.random.PRNGKey(0), p).theta) == 0.0
    # Four-link, hinges all +2pi/9: links at -pi/3, -pi/9, pi/9, pi/3 (mean direction along x).
    p = env.make_params("nlink", init=(1, 1, 1))
    theta = float(env.reset(jax.random.PRNGKey(0), p).theta)
    angles = np.asarray(nlink.link_angles(np.full(3, 2 * math.pi / 9), theta))
    np.testing.assert_allclose(angles, [-math.pi / 3, -math.pi / 9, math.pi / 9, math.pi / 3], atol=1e-6)
    # fidelity.md: the best four-link stroke goes 0.3134 per 6-step cycle along x from this start
    # (0.2945 if the middle link started along x instead).
    cycle = [(3, -1), (2, -1), (1, -1), (3, 1), (2, 1), (1, 1)]
    x = np.asarray(env.rollout("nlink", cycle * 2, init=(1, 1, 1)).x)
    assert x[5] == pytest.approx(0.3134, abs=5e-4) and x[11] == pytest.approx(2 * 0.3134, abs=1e-3)


def test_cycle_and_sign_starts_follow_the_swimmer_s_dofs():
    assert {initial("cycle", k, "nlink") for k in range(8)} == set(env.all_inits(3))
    assert initial("+-", 0, "ng") == (1, 0)
    from jswim.errors import ConfigError

    with pytest.raises(ConfigError, match="3 DOFs"):
        initial("++", 0, "nsphere")
