"""Shared test setup: physics accuracy is asserted in float64."""

import jax

jax.config.update("jax_enable_x64", True)
