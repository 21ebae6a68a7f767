"""General stroke integrators along a straight path in shape space.

The env applies steps from a precomputed table (see `jswim.env`); this module is the ground
truth that builds the table and handles strokes that do not follow it (any start shape, any rates,
any duration). The pose is the reference point ``(x, y)`` and orientation ``theta``; in the lab
frame ``d/dt (x, y) = R(theta) (u, v)`` and ``d theta / dt = omega`` with ``(u, v, omega)`` the
model's body-frame velocity.

Two methods:

* ``"chebyshev"`` (default): the body-frame velocities depend on the shape only, so the ODE is
  two nested quadratures: ``theta(t)`` is the integral of ``omega``, then the position is the
  integral of ``R(theta) (u, v)``. Both are done spectrally on Chebyshev-Lobatto nodes; degree 16
  (17 velocity evaluations) reaches ~1e-14 relative per cycle for the paper's swimmers.
* ``"rk4"``: classical fixed-step Runge-Kutta, kept as an independent reference.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.errors import ConfigError
from jswim.swimmers.models import SwimmerModel

__all__ = ["centroid", "chebyshev_rule", "integrate_stroke", "pose_rate"]


def pose_rate(model: SwimmerModel, d: Array, d_dot: Array, theta: Array) -> Array:
    """Lab-frame rate of the pose ``(x, y, theta)`` of the reference point."""
    u, v, omega = model.body_velocity(d, d_dot)
    c, s = jnp.cos(theta), jnp.sin(theta)
    return jnp.stack([c * u - s * v, s * u + c * v, omega])


@functools.lru_cache(maxsize=8)
def chebyshev_rule(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Chebyshev-Lobatto nodes on [0, 1] and the matrix of running integrals ``int_0^{s_i}``.

    ``S @ f(s)`` approximates the antiderivative of ``f`` at every node with spectral accuracy
    (exact for polynomials of degree <= ``n``).
    """
    x = -np.cos(np.pi * np.arange(n + 1) / n)  # ascending on [-1, 1]
    cheb = np.polynomial.chebyshev
    basis = cheb.chebvander(x, n)  # (nodes, coefficients)
    integ = np.stack(
        [cheb.chebval(x, cheb.chebint(np.eye(n + 1)[k], lbnd=-1)) for k in range(n + 1)], axis=1
    )
    running = integ @ np.linalg.inv(basis) / 2.0  # map [-1, 1] -> [0, 1]
    return (x + 1.0) / 2.0, running


def integrate_stroke(
    model: SwimmerModel,
    d0: Array,
    d_dot: Array,
    duration: Array | float,
    pose0: Array | None = None,
    n_sub: int = 16,
    method: str = "chebyshev",
    dotless: bool = False,
) -> Array:
    """Pose after moving the shape from ``d0`` at constant rate ``d_dot`` for ``duration``.

    Parameters
    ----------
    model : SwimmerModel
        The swimmer.
    d0, d_dot : Array, shape (n_dof,)
        Start shape and constant shape rate.
    duration : float
        Time of the move.
    pose0 : Array, shape (3,), optional
        Start pose ``(x, y, theta)`` of the reference point (default: origin, theta = 0).
    n_sub : int
        Chebyshev: polynomial degree (``n_sub + 1`` velocity evaluations; 16 gives ~1e-14).
        RK4: substeps (error ~ ``n_sub**-4``; 96 gives ~3e-10 per cycle).
    method : str
        ``"chebyshev"`` or ``"rk4"``.
    dotless : bool
        Chebyshev quadrature as sums of products instead of matrix products (the same numbers to
        ~1e-16). For calls traced inside a local ``jax.enable_x64`` under ``vmap`` and ``scan``
        (the environment's float64 steps in batched float32 learners), where XLA lowers a dot at
        the global precision and the step fails on mixed float32/float64 operands.

    Returns
    -------
    Array, shape (3,)
        End pose of the reference point. Works under ``jit`` and ``vmap``.
    """
    d0 = jnp.asarray(d0)
    d_dot = jnp.asarray(d_dot, d0.dtype)
    pose = jnp.zeros(3, d0.dtype) if pose0 is None else jnp.asarray(pose0, d0.dtype)
    duration = jnp.asarray(duration, d0.dtype)
    if method == "chebyshev":
        nodes, running = chebyshev_rule(n_sub)
        t = jnp.asarray(nodes, d0.dtype) * duration
        w = jax.vmap(lambda tk: model.body_velocity(d0 + d_dot * tk, d_dot))(t)  # (nodes, 3)
        s_mat = jnp.asarray(running, d0.dtype) * duration
        if dotless:  # products and sums: no dot for XLA to lower at the global (float32) precision
            theta = pose[2] + jnp.sum(s_mat * w[None, :, 2], axis=1)
        else:
            theta = pose[2] + s_mat @ w[:, 2]
        c, s = jnp.cos(theta), jnp.sin(theta)
        vx, vy = c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1]
        if dotless:
            return jnp.stack(
                [pose[0] + jnp.sum(s_mat[-1] * vx), pose[1] + jnp.sum(s_mat[-1] * vy), theta[-1]]
            )
        return jnp.stack([pose[0] + s_mat[-1] @ vx, pose[1] + s_mat[-1] @ vy, theta[-1]])
    if method != "rk4":
        raise ConfigError(f"method must be 'chebyshev' or 'rk4', got {method!r}")
    h = duration / n_sub

    def rate(t: Array, p: Array) -> Array:
        return pose_rate(model, d0 + d_dot * t, d_dot, p[2])

    def body(k: int, p: Array) -> Array:
        t = k * h
        k1 = rate(t, p)
        k2 = rate(t + h / 2, p + h / 2 * k1)
        k3 = rate(t + h / 2, p + h / 2 * k2)
        k4 = rate(t + h, p + h * k3)
        return p + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    return jax.lax.fori_loop(0, n_sub, body, pose)


def centroid(model: SwimmerModel, d: Array, pose: Array) -> Array:
    """Lab-frame geometric centroid for shape ``d`` and reference pose ``(x, y, theta)``."""
    off = model.centroid_offset(d)
    c, s = jnp.cos(pose[2]), jnp.sin(pose[2])
    return pose[:2] + jnp.stack([c * off[0] - s * off[1], s * off[0] + c * off[1]])
