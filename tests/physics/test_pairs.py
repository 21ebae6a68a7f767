"""A side-by-side pair stroking in phase keeps the mirror through the plane midway between its
axes: equal x, opposite z displacements and tilts, so no x offset drifts (the phase scan of
docs/scenes.md rests on it); out of phase the mirror is broken and the offset drifts."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.scenes import Scene, scene_params, scene_reset, scene_step, scene_step_joint

DOFS = [0, 1, 0, 1]
ROCS = [-1.0, -1.0, 1.0, 1.0]


def _cycles(k: int, cycles: int = 2):
    p = scene_params(
        "ng", Scene(medium="free", swimmers=2, separation=30.0, formation="side"), dtype=jnp.float64
    )
    key = jax.random.PRNGKey(0)
    st = scene_reset(p)
    for j in range(k):  # swimmer 2 k moves ahead
        st = scene_step(p, st, (1, DOFS[j], ROCS[j]), key)[0]
    c0, t0 = np.asarray(st.centre + st.centre_lo), np.asarray(st.tilt)
    for j in range(4 * cycles):
        st = scene_step_joint(
            p,
            st,
            jnp.array([DOFS[j % 4], DOFS[(j + k) % 4]]),
            jnp.array([ROCS[j % 4], ROCS[(j + k) % 4]]),
            key,
        )[0]
    return np.asarray(st.centre + st.centre_lo) - c0, np.asarray(st.tilt) - t0


@pytest.mark.slow  # the pair's joint step compiled: ~1 min under load
def test_in_phase_side_pair_is_mirror_symmetric_and_out_of_phase_is_not():
    with jax.enable_x64(True):
        d, t = _cycles(0)
        assert abs(d[0, 0] - d[1, 0]) < 1e-11  # no x offset drift
        assert abs(d[0, 1] + d[1, 1]) < 1e-11 and abs(t[0] + t[1]) < 1e-11  # mirror
        assert d[1, 1] - d[0, 1] < 0  # they draw together (attract) in phase at 30 a
        d2, _ = _cycles(1)
        assert abs(d2[0, 0] - d2[1, 0]) > 1e-7  # a quarter cycle apart, the offset drifts
