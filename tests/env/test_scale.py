"""Scale: drift-free positions in float32, float64 rollouts without flags, ensembles, sharding.

The sharded-equals-single-device check runs in one subprocess with
``XLA_FLAGS=--xla_force_host_platform_device_count=4`` (the flag must be set before JAX starts)
and JAX's defaults (x64 off); this process computes the one-device reference with x64 off too.
"""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim import env
from jswim.prompt import encode_position
from jswim.studies import ensemble

SQUARE = [(2, -1), (1, -1), (2, 1), (1, 1)]  # Purcell, from (+, +), +x
PURCELL_CYCLE = 0.19124724  # DESIGN.md, d_max = pi/3


def _square_gait_x(n_cycles: int) -> tuple[float, np.dtype]:
    params = env.make_params("purcell")
    acts = jnp.asarray([env.encode_action(*m) for m in SQUARE], jnp.int32)

    @jax.jit
    def run(state):
        def cycle(st, _):
            for a in acts:
                st, _ = env.advance(st, a, jnp.zeros((), st.x.dtype), params)
            return st, None

        return jax.lax.scan(cycle, state, None, length=n_cycles)[0]

    state = run(env.reset(jax.random.PRNGKey(0), params))
    return float(env.position(state)[0]), state.x.dtype


def test_positions_do_not_drift_in_float32(float32):
    """10^6 square-gait steps in the default dtype: X within 1e-9 relative of the closed form.

    The reference is the per-cycle value times 250,000: 0.19124724 (DESIGN.md, 8 digits) refined
    by the float64 rollout, which must agree with it to 5e-9 a per cycle.
    """
    per_cycle = float(env.rollout_moves("purcell", SQUARE).x[-1])
    assert abs(per_cycle - PURCELL_CYCLE) < 5e-9
    x, dtype = _square_gait_x(250_000)
    assert dtype == np.float32
    assert abs(x / (250_000 * per_cycle) - 1.0) < 1e-9
    # The prompt shows the exact position after 10^4 steps: (X/a + 2.5) * 1000, truncated.
    x4, _ = _square_gait_x(2_500)
    assert encode_position(x4) == math.floor((2_500 * per_cycle + 2.5) * 1000) == 480618


def test_rollout_runs_in_float64_without_global_flags(float32):
    import jswim

    assert jnp.result_type(float) == jnp.float32  # the user's default
    r = jswim.env.rollout_moves(
        "purcell", SQUARE * 1000
    )  # the named-swimmer shortcut notebooks use
    assert r.x.dtype == np.float64
    cycles = r.x[3::4]
    np.testing.assert_allclose(np.diff(cycles), cycles[0], rtol=0, atol=1e-12)  # 1e-12 per cycle
    assert abs(cycles[0] - PURCELL_CYCLE) < 5e-9
    assert abs(cycles[-1] / 1000 - cycles[0]) < 1e-12
    # A reciprocal stroke goes nowhere (scallop theorem): 0 to 1e-12 per cycle.
    back_forth = env.rollout_moves("purcell", [(1, -1), (1, 1)] * 1000)
    assert abs(back_forth.x[-1]) < 1e-12 * 1000 and np.abs(back_forth.x[1::2]).max() < 1e-12 * 1000
    batch = env.rollout_moves("ng", np.array([[(1, 1), (2, 1), (1, -1), (2, -1)]] * 3), init=(0, 0))
    assert batch.x.dtype == np.float64 and batch.x.shape == (3, 4)


def test_step_batch_in_float32_keeps_its_dtype_and_unit_rotation(float32):
    params = env.make_params("purcell", zeta=0.5, init="random")
    keys = jax.random.split(jax.random.PRNGKey(0), 257)
    states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
    for t in range(50):
        a = jax.random.randint(jax.random.PRNGKey(100 + t), (257,), 0, 6)
        states, info = env.step_batch(jax.random.PRNGKey(t), states, a, params)
    assert states.x.dtype == jnp.float32 and info.dx.dtype == jnp.float32
    c = np.asarray(states.cos, np.float64) + np.asarray(states.cos_lo, np.float64)
    s = np.asarray(states.sin, np.float64) + np.asarray(states.sin_lo, np.float64)
    np.testing.assert_allclose(np.hypot(c, s), 1.0, atol=1e-13)
    th = np.asarray(states.theta, np.float64) + np.asarray(states.theta_lo, np.float64)
    np.testing.assert_allclose(
        c, np.cos(th), atol=1e-6
    )  # theta itself is reported to float32 accuracy


def test_noise_draws_are_chunkable():
    key = jax.random.PRNGKey(3)
    whole = np.asarray(env.noise(key, 1000, step=7))
    part = np.asarray(env.noise(key, 300, start=400, step=7))
    np.testing.assert_array_equal(whole[400:700], part)
    assert whole.min() >= -1.0 and whole.max() < 1.0
    assert abs(whole.mean()) < 0.1 and abs(whole.var() - 1 / 3) < 0.05
    assert not np.array_equal(whole, np.asarray(env.noise(key, 1000, step=8)))


def test_ensemble_matches_the_closed_form_and_ignores_the_chunk_size(float32):
    """For a fixed stroke, X_t = sum_k dX_k (1 + zeta Y_k): mean = noiseless X_t, variance
    zeta^2/3 sum_k dX_k^2 (exact, from the float64 rollout's increments)."""
    params = env.make_params("purcell")
    policy = ensemble.stroke_policy([env.encode_action(*m) for m in SQUARE])
    n, steps = 3 * ensemble.BLOCK + 100, 12
    a = ensemble.run(policy, params, n=n, zetas=(0.0, 1.5), steps=steps, chunk=ensemble.BLOCK)
    b = ensemble.run(policy, params, n=n, zetas=(1.5,), steps=steps, chunk=4 * ensemble.BLOCK)
    for field in ("mean", "std", "quantiles", "min", "max", "forward"):
        np.testing.assert_array_equal(getattr(a[1], field), getattr(b[0], field))
    clean = env.rollout_moves("purcell", SQUARE * 3)
    dx = np.diff(np.concatenate([[0.0], clean.x]))
    np.testing.assert_allclose(a[0].mean, clean.x, atol=1e-6)
    assert np.all(a[0].std < 1e-6) and np.all(a[0].forward == 1.0)
    sd = np.sqrt(1.5**2 / 3 * np.cumsum(dx**2))
    np.testing.assert_allclose(a[1].std, sd, rtol=0.03)
    assert np.all(np.abs(a[1].mean - clean.x) < 5 * sd / math.sqrt(n))
    med = a[1].quantiles[:, a[1].qs.index(0.5)]
    assert np.all(np.abs(med - clean.x) < 0.05 * sd + a[1].resolution)  # symmetric law
    assert np.all(a[1].min <= a[1].quantiles[:, 0]) and np.all(a[1].quantiles[:, -1] <= a[1].max)


@pytest.mark.slow  # trains a Q-learner, then a 40-step ensemble (3.5 CPU-s); the closed-form ensemble test stays fast
def test_ensemble_q_policy_swims_the_square_gait(float32):
    params = env.make_params("purcell")
    pol = ensemble.learned_policy(params, seed=0)
    [s] = ensemble.run(pol, params, n=ensemble.BLOCK, zetas=(0.0,), steps=40, every=4)
    assert s.mean[-1] == pytest.approx(10 * PURCELL_CYCLE, rel=1e-3)


def _scaled_cases():
    """The batched paths on small inputs; returns a dict of NumPy arrays (x64 off)."""
    from jswim.agents import qlearning

    out = {}
    params = env.make_params("purcell", init="random")
    b = 1001  # not a multiple of the device count: padded and cut back
    states = jax.vmap(env.reset, in_axes=(0, None))(
        jax.random.split(jax.random.PRNGKey(0), b), params
    )
    zetas = env.broadcast_params(params, b, zeta=np.linspace(0, 2, b))
    for t in range(5):
        a = jax.random.randint(jax.random.PRNGKey(10 + t), (b,), 0, 6)
        states, info = env.step_batch(jax.random.PRNGKey(t), states, a, zetas)
    out["step_batch_x"], out["step_batch_lo"] = np.asarray(states.x), np.asarray(states.x_lo)
    out["step_batch_progress"] = np.asarray(info.progress)
    ng = env.make_params("ng", direction=-1)
    run = qlearning.train(
        env.make("ng")[0],
        ng,
        jax.random.split(jax.random.PRNGKey(1), 103),
        qlearning.QConfig(steps=30),
    )
    out["q_actions"], out["q_x"], out["q_table"] = (
        np.asarray(v) for v in (run.actions, run.x, run.q)
    )
    r = env.rollout_moves("purcell", np.tile(np.array(SQUARE), (6, 2, 1)), zeta=0.8, key=5)
    out["rollout_x"] = r.x
    pol = ensemble.stroke_policy([env.encode_action(*m) for m in SQUARE])
    [s] = ensemble.run(
        pol,
        env.make_params("purcell"),
        n=2 * ensemble.BLOCK + 10,
        zetas=(1.0,),
        steps=8,
        chunk=ensemble.BLOCK,
    )
    out["ens_mean"], out["ens_std"], out["ens_q"], out["ens_fwd"] = (
        s.mean,
        s.std,
        s.quantiles,
        s.forward,
    )
    return out


_CHILD = """
import json, sys, numpy as np, jax
assert jax.device_count() == 4, jax.devices()
assert not jax.config.jax_enable_x64
sys.path.insert(0, {root!r})
from tests.env.test_scale import _scaled_cases
np.savez({out!r}, **_scaled_cases())
x, _ = __import__("tests.env.test_scale", fromlist=["_square_gait_x"])._square_gait_x(2500)
print(json.dumps({{"x": x, "devices": jax.device_count()}}))
"""


@pytest.mark.slow  # a fresh interpreter with 4 host devices recompiles every batched path (83 s under load 8)
def test_four_host_devices_give_the_numbers_of_one(tmp_path, float32):
    root = str(Path(__file__).resolve().parents[2])
    out = tmp_path / "sharded.npz"
    envvars = {k: v for k, v in os.environ.items() if k not in ("JAX_ENABLE_X64", "JAX_PLATFORMS")}
    envvars["XLA_FLAGS"] = (
        envvars.get("XLA_FLAGS", "") + " --xla_force_host_platform_device_count=4"
    ).strip()
    envvars["JAX_PLATFORMS"] = "cpu"
    proc = subprocess.run(
        [sys.executable, "-c", _CHILD.format(root=root, out=str(out))],
        env=envvars,
        capture_output=True,
        text=True,
        timeout=600,
        cwd=root,
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    child = json.loads(proc.stdout.strip().splitlines()[-1])
    assert child["devices"] == 4
    sharded = np.load(out)
    single = _scaled_cases()
    assert set(sharded.files) == set(single)
    for name in single:
        np.testing.assert_array_equal(sharded[name], single[name], err_msg=name)
    assert child["x"] == _square_gait_x(2500)[0]


def test_ensemble_command(tmp_path, capsys):
    from jswim import cli

    out = tmp_path / "ens.csv"
    rc = cli.main(
        [
            "ensemble",
            "--n",
            "300",
            "--zetas",
            "0,1",
            "--steps",
            "8",
            "--every",
            "2",
            "--out",
            str(out),
        ]
    )
    assert rc == 0
    text = capsys.readouterr().out
    assert "signature gait" in text and "swimmer-steps" in text
    lines = out.read_text().splitlines()
    assert len(lines) == 1 + 2 * 4 and lines[0].startswith("zeta,n,step,mean,std")
    for bad, word in (
        (["--n", "0"], "--n"),
        (["--policy", "3,1"], "dof"),
        (["--zetas", "-1"], "zetas"),
        (["--every", "9", "--steps", "8"], "every"),
        (["--out", str(tmp_path / "no" / "x.csv"), "--n", "10", "--steps", "1"], "--out"),
    ):
        assert cli.main(["ensemble", *bad]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and word in err, err


@pytest.mark.slow  # compiles the Q-learning study for several chunk sizes (26 s under load 8)
def test_qlearn_study_does_not_depend_on_the_chunk():
    from jswim.agents.qlearning import QConfig
    from jswim.studies import qlearn

    cfg = QConfig(steps=30, action_set="shape-changing")
    kw = dict(swimmers=("ng",), directions=(1, -1), n_seeds=40, seed=3)
    seen = []
    whole = qlearn.study(cfg, **kw)
    parts = qlearn.study(
        cfg, chunk=16, progress=lambda done, total: seen.append((done, total)), **kw
    )
    assert whole == parts
    assert seen[-1] == (80, 80) and len(seen) == 5


def test_plain_steps_of_the_baselines_agree_with_exact_steps_over_a_training_run(float32):
    """``advance(exact=False)`` (the baselines' 200-step runs) matches the exact step to 1e-5 a."""
    params = env.make_params("purcell", zeta=0.7)
    acts = jax.random.randint(jax.random.PRNGKey(0), (200,), 0, 6)
    ys = env.noise(jax.random.PRNGKey(1), 200)

    def run(exact):
        def body(st, inp):
            st, info = env.advance(st, inp[0], inp[1], params, exact=exact)
            return st, info.x

        return np.asarray(
            jax.lax.scan(body, env.reset(jax.random.PRNGKey(0), params), (acts, ys))[1]
        )

    fast, exact = run(False), run(True)
    assert fast.dtype == np.float32 and np.abs(exact).max() > 0.1
    np.testing.assert_allclose(fast, exact, rtol=0, atol=1e-5)
