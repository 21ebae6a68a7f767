"""Shared test setup.

Physics accuracy is asserted in float64, so x64 is on for the suite. Users run with JAX's
default (x64 off, float32), so the ``float32`` fixture runs a test under
``jax.enable_x64(False)``: the dtype users get, in-process (one subprocess test,
tests/test_scale.py, also checks a fresh interpreter with JAX's defaults and 4 host devices).
"""

import os
import tempfile

import jax
import pytest

jax.config.update("jax_enable_x64", True)
# The exact tables' disk cache (jswim.env.cache) goes to a fresh folder, never the user's.
os.environ["JSWIM_TABLE_CACHE"] = tempfile.mkdtemp(prefix="jswim-test-tables-")


@pytest.fixture
def float32():
    """Run the test with x64 off, as a user's session is by default."""
    with jax.enable_x64(False):
        yield
