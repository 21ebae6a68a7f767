"""The world protocol (jswim.env.base): both worlds step through it exactly as through their own
API, in the users' float32 and in float64; one rollout and one batched rollout serve both; every
old name still imports from its old place."""

import importlib
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim import env as jenv
from jswim.env.base import Environment, StepInfo
from jswim.env.episodes import rollout
from jswim.env.scene_world import SceneWorld
from jswim.env.swimmer_world import SwimmerWorld
from jswim.errors import ConfigError
from jswim.env import scene_rollout
from jswim.scenes import Scene, decode_scene_action, scene_reset, scene_step

#: The square gait (DOF 2 down, DOF 1 down, DOF 2 up, DOF 1 up) as (dof, roc) and as codes.
SQUARE = [(2, -1), (1, -1), (2, 1), (1, 1)]
SQUARE_CODES = [jenv.encode_action(d, r) for d, r in SQUARE]


def _equal_trees(a, b):
    la, lb = jax.tree.leaves(a), jax.tree.leaves(b)
    assert len(la) == len(lb)
    for x, y in zip(la, lb):
        assert np.asarray(x).dtype == np.asarray(y).dtype
        np.testing.assert_array_equal(np.asarray(x), np.asarray(y))


def _paper_steps(swimmer, actions, zeta=0.7):
    env, params = jswim.make(swimmer, zeta=zeta, direction="-x")
    key = jax.random.PRNGKey(3)
    s_new = s_old = env.reset(key, params)
    _equal_trees(s_new, jenv.reset(key, params))
    for i, a in enumerate(actions):
        k = jax.random.fold_in(key, i)
        s_new, info = env.step(k, s_new, a, params)
        s_old, old = jenv.step(k, s_old, a, params)
        _equal_trees(s_new, s_old)
        np.testing.assert_array_equal(info.displacement, np.stack([old.dx, old.dy])[None])
        np.testing.assert_array_equal(info.progress, old.progress)
        np.testing.assert_array_equal(info.stuck, old.stuck)
        assert not bool(info.contact) and math.isinf(float(info.gap))
    return s_new, info


@pytest.mark.parametrize(
    "swimmer", [pytest.param("purcell", marks=pytest.mark.slow), "ng"]
)  # Purcell: motion table
def test_paper_world_steps_bit_equal_to_env_step_float32(float32, swimmer):
    codes = [jnp.int32(c) for c in SQUARE_CODES + [SQUARE_CODES[0]] * 2]  # the last one is stuck
    rocs = [jnp.array([0.0, -0.3]), jnp.array([0.5, 0.2])]  # real ROCs: the continuous path
    state, info = _paper_steps(swimmer, codes + rocs)
    assert state.x.dtype == jnp.float32 and info.progress.dtype == jnp.float32
    assert info.displacement.shape == (1, 2)


@pytest.mark.slow
def test_paper_world_steps_bit_equal_float64():
    _paper_steps("purcell", [jnp.int32(c) for c in SQUARE_CODES] + [jnp.array([0.25, 0.0])])


@pytest.mark.slow
@pytest.mark.parametrize(
    "scene",
    [
        Scene(medium="wall", height=4.0),
        Scene(medium="free", swimmers=2, separation=25.0),
        Scene(medium="bulk", tilt=0.3),
    ],
    ids=["wall", "pair", "tilted-bulk"],
)
def test_scene_world_steps_bit_equal_to_scene_step_float32(float32, scene):
    env, task = jswim.make("ng", scene, zeta=0.5)
    assert isinstance(env, SceneWorld) and env.n_swimmers == scene.swimmers
    sp = task.scene
    assert sp.arms0.dtype == jnp.float32
    s_new = env.reset(jax.random.PRNGKey(0), task)
    s_old = scene_reset(sp)
    _equal_trees(s_new, s_old)
    key = jax.random.PRNGKey(5)
    codes = [0, 3, 2, 5] if scene.swimmers == 1 else [6, 0, 9, 3]
    for i, c in enumerate(codes):
        k = jax.random.fold_in(key, i)
        s_new, info = env.step(k, s_new, jnp.int32(c), task)
        s_old, old = scene_step(sp, s_old, decode_scene_action(jnp.int32(c)), k)
        _equal_trees(s_new, s_old)
        np.testing.assert_array_equal(info.contact, old.contact)
        np.testing.assert_array_equal(info.gap, old.gap)
        assert info.displacement.shape == (scene.swimmers, 2) and info.progress.dtype == jnp.float32
    # A ROC vector moves its first non-zero entry, as the code of that arm does.
    vec = jnp.zeros(env.n_dof).at[1].set(1.0)
    a, _ = env.step(key, s_new, vec, task)
    b, _ = env.step(key, s_new, jnp.int32(jenv.encode_action(2, 1)), task)
    _equal_trees(a, b)


@pytest.mark.slow
def test_rollout_serves_both_worlds_as_their_own_rollouts():
    # The paper's world: the old rollout (float64) and the protocol's, same key, same numbers.
    old = jswim.env.rollout_moves("ng", SQUARE * 2, key=4, zeta=0.3)
    with jax.enable_x64(True):
        env, params = jswim.make("ng", zeta=0.3)
        tr = jswim.rollout(env, params, 4, jnp.array(SQUARE_CODES * 2, jnp.int32))
    np.testing.assert_array_equal(np.asarray(tr.obs.position[:, 0, 0]), old.x)
    np.testing.assert_array_equal(np.asarray(tr.info.progress), old.progress)
    np.testing.assert_array_equal(np.asarray(tr.obs.dofs), old.dofs)
    # A scene: scene_rollout and the protocol's rollout of the same joint codes.
    scene = Scene(medium="wall", height=5.0)
    old = scene_rollout("ng", SQUARE, scene, key=2)
    with jax.enable_x64(True):
        env, task = jswim.make("ng", scene, dtype="float64")
        tr = rollout(env, task, 2, jnp.array(SQUARE_CODES, jnp.int32))
    np.testing.assert_array_equal(np.asarray(tr.state.centre[..., 0]), old.x)
    np.testing.assert_array_equal(np.asarray(tr.state.arms), old.arms)
    np.testing.assert_array_equal(np.asarray(tr.info.gap), old.gap)


def test_progress_toward_minus_x_is_minus_the_closed_form():
    # Independent numbers (docs/design.md): Purcell d_max = pi/3 and NG (6, 10) per square cycle.
    for swimmer, per_cycle in (("purcell", 0.19124724), ("ng", 0.15626494)):
        with jax.enable_x64(True):
            totals = {}
            for direction, sign in (("+x", 1.0), ("-x", -1.0)):
                env, params = jswim.make(swimmer, direction=direction)
                tr = rollout(env, params, 0, jnp.array(SQUARE_CODES * 3, jnp.int32))
                totals[direction] = float(jnp.sum(tr.info.progress))
                np.testing.assert_array_equal(
                    tr.info.progress, sign * tr.info.displacement[:, 0, 0]
                )
            # This gait swims Purcell's swimmer toward +x and NG's toward -x.
            assert abs(totals["+x"]) == pytest.approx(3 * per_cycle, rel=1e-7)
            assert totals["-x"] == -totals["+x"]


def test_scene_progress_follows_direction_and_the_centroid():
    scene = Scene(medium="free", swimmers=1)
    with jax.enable_x64(True):
        env, plus = jswim.make("ng", scene, dtype="float64")
        _, minus = jswim.make("ng", scene, dtype="float64", direction=-1)
        actions = jnp.array(SQUARE_CODES * 2, jnp.int32)
        a, b = rollout(env, plus, 0, actions), rollout(env, minus, 0, actions)
    np.testing.assert_array_equal(np.asarray(b.info.progress), -np.asarray(a.info.progress))
    # After whole cycles the shape is back, so the centroid moved as the middle sphere did.
    total = float(jnp.sum(a.info.progress))
    assert total == pytest.approx(float(a.state.centre[-1, 0, 0]), rel=1e-12)
    # An isolated swimmer in the point-force model swims as the paper's formula says (this gait
    # toward -x, 0.156 a per cycle there), a little faster.
    assert 0.1 < -total / 2 < 0.2


def test_scene_observation_heights_are_the_middle_sphere_s_positions_the_full_centroid(float32):
    # A hand-built float32 state: arms (10, 6), tilt 0.3, the middle sphere at x = 1e4 + 1e-4 held
    # as the pair centre + centre_lo (1e4 alone is float32's nearest; its spacing there is 9.8e-4).
    env, task = jswim.make("ng", Scene(medium="wall", height=6.0))
    state = env.reset(jax.random.PRNGKey(0), task)._replace(
        arms=jnp.array([[10.0, 6.0]], jnp.float32),
        tilt=jnp.array([0.3], jnp.float32),
        centre=jnp.array([[1e4, 6.0]], jnp.float32),
        centre_lo=jnp.array([[1e-4, 0.0]], jnp.float32),
    )
    obs = env.observe(state, task)
    # The centroid: (d2 - d1) / 3 = -4/3 a along the axis; the height H: the middle sphere's z.
    assert obs.height.dtype == jnp.float32 and float(obs.height[0]) == 6.0
    assert float(obs.position[0, 1]) == pytest.approx(6.0 - 4 / 3 * math.sin(0.3), abs=1e-6)
    assert float(obs.position[0, 0]) == pytest.approx(1e4 - 4 / 3 * math.cos(0.3), abs=1e-3)
    # Widened to float64 (as the LLM's step group reads X), the low word counts: drift-free.
    with jax.enable_x64(True):
        wide = env.observe(
            jax.tree.map(lambda a: a.astype(jnp.float64) if a.dtype == jnp.float32 else a, state),
            task,
        )
        x = float(wide.position[0, 0])
    assert x == pytest.approx(
        1e4 + float(np.float32(1e-4)) - 4 / 3 * math.cos(np.float32(0.3)), abs=1e-9
    )
    # The paper's world is seen from above: its height is its position's y, always given.
    env, params = jswim.make("ng")
    obs = env.observe(env.reset(jax.random.PRNGKey(0), params), params)
    assert obs.height.shape == (1,) and float(obs.height[0]) == float(obs.position[0, 1])
    assert not env.scenery().side_view


@pytest.mark.slow
def test_vmapped_batch_equals_each_member(float32):
    env, params = jswim.make("purcell", zeta=1.0)
    actions = jnp.array(
        [
            SQUARE_CODES * 2,
            SQUARE_CODES[::-1] * 2,
            SQUARE_CODES[1:] + SQUARE_CODES + SQUARE_CODES[:1],
        ],
        jnp.int32,
    )
    batch = rollout(env, params, 7, actions)
    keys = jax.random.split(jenv.seed_key(7), 3)
    for i in range(3):
        one = rollout(env, params, keys[i], actions[i])
        _equal_trees(jax.tree.map(lambda v: v[i], batch), one)
    assert batch.info.progress.shape == (3, 8) and batch.info.progress.dtype == jnp.float32
    # A direction per member (the world says which leaves carry the batch axis).
    both = jenv.broadcast_params(params, 2, zeta=0.0, direction=np.array([1.0, -1.0]))
    tr = rollout(env, both, 0, jnp.array([SQUARE_CODES] * 2, jnp.int32))
    np.testing.assert_array_equal(tr.info.progress[0], -tr.info.progress[1])


def test_spaces_sizes_and_make_errors():
    env, params = jswim.make("purcell", roc_levels=2)
    assert (env.n_dof, env.n_actions, env.n_swimmers) == (2, 10, 1)
    codes = jax.vmap(env.action_space(params).sample)(jax.random.split(jax.random.PRNGKey(0), 500))
    assert set(np.unique(codes).tolist()) == set(range(10))
    vec = env.roc_space(params).sample(jax.random.PRNGKey(1))
    assert vec.shape == (2,) and bool(env.roc_space(params).contains(vec))
    assert hash(env) == hash(jswim.make("purcell", roc_levels=2)[0])  # static: one compilation
    pair, _ = jswim.make("ng", Scene(medium="wall", swimmers=2))
    assert (pair.n_dof, pair.n_actions, pair.n_swimmers, pair.n_features) == (4, 12, 2, 8)
    # A plain bulk scene is the paper's world.
    plain, p = jswim.make("ng", Scene())
    assert isinstance(plain, SwimmerWorld) and isinstance(p, jenv.EnvParams)
    for bad in ({"medium": "sea"}, 3):
        with pytest.raises(ConfigError):
            jswim.make("ng", bad)
    with pytest.raises(ConfigError):  # Purcell above a wall is built; in "free" it is not
        jswim.make("purcell", Scene(medium="free"))
    with pytest.raises(ConfigError):
        jswim.make("purcell", dtype="float64")
    assert isinstance(env, Environment) and StepInfo._fields[:2] == ("displacement", "progress")


def test_old_names_import_from_their_old_places():
    for module, names in {
        "jswim.env": [
            "EnvParams",
            "EnvState",
            "StepInfo",
            "Rollout",
            "make_params",
            "reset",
            "step",
            "step_batch",
            "advance",
            "rollout_moves",
            "seed32",
            "seed_key",
            "encode_action",
            "dof_values",
            "position",
        ],
        "jswim.env.rollouts": ["Rollout", "rollout_moves", "seed32", "seed_key"],
        "jswim.env.scene_rollouts": ["SceneRollout", "scene_rollout", "scene_rollout_batch"],
        "jswim.scenes": [
            "Scene",
            "SceneParams",
            "SceneState",
            "SceneStepInfo",
            "scene_params",
            "scene_reset",
            "scene_step",
            "scene_step_joint",
            "scene_advance",
            "batch_starts",
            "decode_scene_action",
            "encode_scene_action",
        ],
        "jswim": ["rollout", "make_params", "reset", "step", "step_batch", "make"],
        # defined elsewhere, still importable from these modules
        "jswim.results": ["atomic_write", "write_json", "dumps", "plain_json"],
        "jswim.studies.scene_studies": ["fate", "scene_row"],
        "jswim.studies.scene_grids": [
            "wall_scene",
            "pair_scene",
            "wall_cells",
            "pair_cells",
            "school_cells",
        ],
    }.items():
        mod = importlib.import_module(module)
        for name in names:
            assert callable(getattr(mod, name)) or isinstance(getattr(mod, name), type), (
                module,
                name,
            )


@pytest.mark.slow
def test_old_rollout_with_a_scene_routes_to_the_scene_rollout():
    r = jswim.env.rollout_moves("ng", SQUARE, scene=Scene(medium="wall", height=5.0))
    assert r.z.shape == (4, 1) and r.contact.shape == (4,)
