"""Background flows and the rigid motion they give a link swimmer, checked as a referee would:
Galilean invariance, Jeffery's slender-body tumbling in shear (closed form, and integrated over
time), Poiseuille's local shear, and a small passive body keeping to a Taylor-Green streamline;
each flow's gradient and hessian against its velocity. In float64 and in the default float32."""

from __future__ import annotations

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.env.flows import (
    FLOWS,
    Poiseuille,
    Shear,
    TaylorGreen,
    Uniform,
    flow_from_dict,
)
from jswim.errors import ConfigError
from jswim.swimmers.flow_response import flow_velocity

SHAPES = [(0.0, 0.0), (0.6, -0.4), (-1.0, 1.0), (0.3, 0.9)]
TOL = {"float64": 1e-12, "float32": 2e-6}


@pytest.fixture(params=["float64", "float32"])
def dtype(request):
    if request.param == "float64":
        yield jnp.float64
    else:
        with jax.enable_x64(False):
            yield jnp.float32


def _tol(dtype) -> float:
    return TOL[jnp.dtype(dtype).name]


@pytest.mark.parametrize("shape", SHAPES)
def test_a_uniform_flow_carries_any_shape_with_it_and_turns_nothing(shape, dtype):
    flow = Uniform((0.02, -0.013))
    pose = jnp.asarray([1.5, -2.0, 0.7], dtype)
    got = flow_velocity(jnp.asarray(shape, dtype), pose, flow.velocity)
    assert got.dtype == dtype
    np.testing.assert_allclose(np.asarray(got), [0.02, -0.013, 0.0], atol=_tol(dtype) * 0.1)


@pytest.mark.parametrize("phi", [0.0, 0.3, math.pi / 4, 1.2, math.pi / 2, 2.5])
@pytest.mark.parametrize("xi_ratio", [2.0, 1.5])
def test_a_straight_rod_in_shear_turns_as_jeffery_s_slender_limit(phi, xi_ratio, dtype):
    gamma = 0.05
    pose = jnp.asarray([0.0, 0.0, phi], dtype)
    u, v, omega = flow_velocity(jnp.zeros(2, dtype), pose, Shear(gamma).velocity, xi_ratio)
    # Jeffery (1922) for aspect ratio -> infinity: d phi / dt = -gamma sin^2 phi; the rod's
    # centre, on the streamline y = 0, does not move.
    assert float(omega) == pytest.approx(-gamma * math.sin(phi) ** 2, abs=_tol(dtype) * 0.1)
    assert abs(float(u)) < _tol(dtype) * 0.1 and abs(float(v)) < _tol(dtype) * 0.1
    # Off the centre line the rod is carried at the local flow speed, with the same rotation.
    off = flow_velocity(jnp.zeros(2, dtype), pose.at[1].set(3.0), Shear(gamma).velocity, xi_ratio)
    np.testing.assert_allclose(
        np.asarray(off), [3.0 * gamma, 0.0, float(omega)], atol=_tol(dtype) * 0.2
    )


def test_jeffery_s_orbit_integrated_over_time_matches_its_closed_form():
    # cot(phi(t)) = cot(phi0) + gamma t, integrated with RK4 from the RFT rotation rate
    gamma, phi0, dt, n = 0.1, 2.0, 0.05, 400
    rate = jax.jit(
        lambda phi: flow_velocity(jnp.zeros(2), jnp.stack([0.0, 0.0, phi]), Shear(gamma).velocity)[
            2
        ]
    )
    phi = jnp.asarray(phi0)
    for _ in range(n):
        k1 = rate(phi)
        k2 = rate(phi + dt / 2 * k1)
        k3 = rate(phi + dt / 2 * k2)
        k4 = rate(phi + dt * k3)
        phi = phi + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    t = n * dt
    expected = math.atan2(1.0, 1.0 / math.tan(phi0) + gamma * t)  # in (0, pi)
    assert float(phi) == pytest.approx(expected, abs=1e-9)


@pytest.mark.parametrize("y", [-0.8, 0.0, 0.5])
def test_poiseuille_turns_a_rod_with_its_local_shear(y, dtype):
    u_max, h, phi = 0.04, 2.0, 1.1
    pose = jnp.asarray([0.0, y, phi], dtype)
    u, _, omega = flow_velocity(jnp.zeros(2, dtype), pose, Poiseuille(u_max, h).velocity)
    local_rate = -2.0 * u_max * y / h**2  # du/dy at the rod's centre
    assert float(omega) == pytest.approx(-local_rate * math.sin(phi) ** 2, abs=_tol(dtype))
    # the centre moves at the flow's speed there, less the curvature's average over the rod:
    # u_max (1 - (y^2 + sin^2(phi) / 4) / h^2) for a rod of length 3 (the mean of s^2 on it: 3/4)
    mean = u_max * (1.0 - (y * y + 0.75 * math.sin(phi) ** 2) / h**2)
    assert float(u) == pytest.approx(mean, abs=_tol(dtype))


def test_a_small_passive_body_keeps_to_its_taylor_green_streamline():
    def drift(cell: float) -> float:
        flow = TaylorGreen(0.05, cell)
        shape = jnp.asarray([0.4, -0.3])
        rate = jax.jit(lambda p: flow_velocity(shape, p, flow.velocity, nodes=6))
        pose = jnp.asarray([0.3 * cell, 0.4 * cell, 0.2])
        psi0 = float(flow.stream(pose[:2]))
        dt = 0.02 * cell / 0.05
        worst = 0.0
        for _ in range(300):
            k1 = rate(pose)
            k2 = rate(pose + dt / 2 * k1)
            k3 = rate(pose + dt / 2 * k2)
            k4 = rate(pose + dt * k3)
            pose = pose + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            worst = max(worst, abs(float(flow.stream(pose[:2])) - psi0))
        return worst / (flow.u0 / flow.k)  # relative to the cell's stream-function range

    near, far = drift(20.0), drift(80.0)
    # A body L = 3 links long in cells many links wide follows the flow: over six turnover times
    # the stream function at its reference point stays within (L / cell)^2 of its start (of the
    # cell's range), and that falls as the square of the cell's size (16x here; at least 10x).
    assert near < (3 / 20) ** 2 and far < (3 / 80) ** 2 and far < near / 10


def test_flow_gradients_are_the_velocity_s_jacobian():
    x = jnp.asarray([[0.3, -1.2], [2.0, 0.7]])
    for flow in (Uniform((0.1, 0.2)), Shear(0.3), Poiseuille(0.05, 1.5), TaylorGreen(0.04, 7.0)):
        jac = jax.vmap(jax.jacfwd(flow.velocity))(x)
        np.testing.assert_allclose(np.asarray(flow.gradient(x)), np.asarray(jac), atol=1e-14)
        div = jnp.trace(flow.gradient(x), axis1=-2, axis2=-1)
        np.testing.assert_allclose(np.asarray(div), 0.0, atol=1e-14)  # incompressible


@pytest.mark.parametrize(
    "flow",
    [Uniform((0.1, 0.2)), Shear(0.3), Poiseuille(0.05, 1.5), TaylorGreen(0.04, 7.0)],
    ids=str,
)
def test_flow_hessians_are_the_gradient_s_derivative_by_finite_differences(flow):
    # central differences of the gradient (error ~ h^2 |d^3 u|) and forward-mode AD agree
    x = jnp.asarray([[0.3, -1.2], [2.0, 0.7], [-4.1, 3.3]])
    h = 1e-5
    fd = jnp.stack(
        [
            (flow.gradient(x + h * jnp.eye(2)[k]) - flow.gradient(x - h * jnp.eye(2)[k])) / (2 * h)
            for k in range(2)
        ],
        axis=-1,
    )
    hess = flow.hessian(x)
    assert hess.shape == (3, 2, 2, 2) and hess.dtype == x.dtype
    np.testing.assert_allclose(np.asarray(hess), np.asarray(fd), rtol=0, atol=1e-10)
    jac = jax.vmap(jax.jacfwd(flow.gradient))(x)
    np.testing.assert_allclose(np.asarray(hess), np.asarray(jac), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(np.asarray(hess), np.asarray(jnp.swapaxes(hess, -1, -2)))
    # incompressible: the divergence's gradient vanishes too
    np.testing.assert_allclose(np.asarray(jnp.einsum("...iik->...k", hess)), 0.0, atol=1e-15)


def test_flows_are_hashable_round_trip_and_refuse_bad_fields():
    flows = [Uniform((0.02, 0.0)), Shear(0.1), Poiseuille(0.03, 4.0), TaylorGreen(0.02, 12.0)]
    assert len({hash(f) for f in flows}) == 4 and set(FLOWS) == {f.kind for f in flows}
    for f in flows:
        assert flow_from_dict(f.to_dict()) == f
    for bad in (
        lambda: Uniform((0.1,)),
        lambda: Uniform(("0.1", 0.0)),
        lambda: Shear(float("nan")),
        lambda: Shear(True),
        lambda: Poiseuille(0.1, 0.0),
        lambda: TaylorGreen(0.1, -1.0),
        lambda: flow_from_dict({"kind": "vortex"}),
        lambda: flow_from_dict({"kind": "shear", "speed": 1.0}),
    ):
        with pytest.raises(ConfigError):
            bad()


@pytest.mark.parametrize(
    "number",
    [np.float32(0.01), np.float64(0.01), np.float16(0.01), jnp.float32(0.01), np.array(0.01)],
    ids=["np.float32", "np.float64", "np.float16", "jnp.float32", "0-d array"],
)
def test_a_flow_takes_the_real_numbers_users_hold_as_the_float_they_hold(number):
    # The flow is the one made from the plain float (same hash: one jit compilation), and its
    # numbers are Python floats, whatever the array type.
    plain = float(number)
    for made, same in (
        (Shear(number), Shear(plain)),
        (Uniform((number, 0)), Uniform((plain, 0.0))),
        (Uniform(np.array([number, 0.0], np.asarray(number).dtype)), Uniform((plain, 0.0))),
        (Poiseuille(number, np.int64(4)), Poiseuille(plain, 4.0)),
        (TaylorGreen(number, jnp.int32(6)), TaylorGreen(plain, 6.0)),
    ):
        assert made == same and hash(made) == hash(same)
        assert all(type(v) is float for v in jax.tree_util.tree_leaves(dataclasses.astuple(made)))


@pytest.mark.parametrize(
    "bad",
    [np.bool_(True), 1j, np.complex64(1), np.array([0.01, 0.02]), "0.01", None, np.float32("nan")],
    ids=["np.bool_", "complex", "np.complex64", "vector", "str", "None", "nan"],
)
def test_a_flow_refuses_what_is_not_one_finite_real_number(bad):
    with pytest.raises(ConfigError, match="flow rate must be a"):
        Shear(bad)
