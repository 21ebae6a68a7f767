"""Real numbers as users hold them: Python's, NumPy's (``np.float32(0.01)``, a value read from an
array) and 0-d arrays (``jnp.float32(0.01)``), never a bool.

Static configurations (flows, learners' hyperparameters, scenes) are hashed into jit's cache, so
they keep the plain Python number a NumPy scalar holds (`plain`): ``Shear(np.float32(0.01))`` and
``Shear(0.009999999776482582)`` are one flow and one compilation.
"""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np

__all__ = ["is_integer", "is_real", "plain"]


def _scalar(value: Any, kind: type, dtype_kinds: str) -> bool:
    # A bool is an Integral to Python; a JAX 0-d array is no numbers.* instance, so its dtype says.
    if isinstance(value, (bool, np.bool_)):
        return False
    if isinstance(value, kind):
        return True
    dtype, shape = getattr(value, "dtype", None), getattr(value, "shape", None)
    return shape == () and dtype is not None and np.dtype(dtype).kind in dtype_kinds


def is_real(value: Any) -> bool:
    """Whether ``value`` is a real scalar: an int or float of Python or NumPy, or a 0-d integer or
    floating array (NumPy, JAX); not a bool, a complex, a string or an array with a shape."""
    return _scalar(value, numbers.Real, "iuf")


def is_integer(value: Any) -> bool:
    """Whether ``value`` is an integer scalar (Python's or NumPy's, or a 0-d integer array); not a
    bool and not a float that happens to be whole."""
    return _scalar(value, numbers.Integral, "iu")


def plain(value: Any) -> Any:
    """The Python ``int`` or ``float`` a real scalar holds (`is_integer` first); anything else
    (a Python number, a bool, a schedule, ``None``, a bad value for the caller to refuse) as it
    is."""
    if isinstance(value, (bool, int, float)) or not is_real(value):
        return value
    return int(value) if is_integer(value) else float(value)
