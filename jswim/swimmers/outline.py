"""The body outline of a swimmer's shape: what every picture of it draws (the report page, the GIF,
the figures' stroke sketches)."""

from __future__ import annotations

from typing import Any

import numpy as np

from jswim.swimmers.models import SwimmerModel


def outline(model: SwimmerModel, d: Any) -> np.ndarray:
    """Body-frame outline of shapes ``d``, centred on the geometric centroid.

    Parameters
    ----------
    model : SwimmerModel
    d : array (..., n_dof)
        DOF values: hinge angles (rad) or arm lengths (in ``a``).

    Returns
    -------
    ndarray (..., P, 2), float64
        Link swimmers: the ``n_dof + 2`` link end points, the reference link (index
        ``n_dof // 2``) along +x and the centroid of the links (the mean of their centres, as
        [`jswim.swimmers.nlink.centroid_offset`][jswim.swimmers.nlink.centroid_offset]) at the origin. Sphere swimmers: the
        ``n_dof + 1`` sphere centres on the x axis, their mean at the origin.
    """
    d = np.asarray(d, np.float64)
    zero = np.zeros(d.shape[:-1] + (1,))
    cum = np.concatenate([zero, np.cumsum(d, axis=-1)], axis=-1)
    if model.planar:
        m = model.n_dof // 2
        phi = cum - cum[..., m : m + 1]  # link angles, the reference link at 0
        t = np.stack([np.cos(phi), np.sin(phi)], axis=-1)  # unit links
        joints = np.concatenate([np.zeros(d.shape[:-1] + (1, 2)), np.cumsum(t, axis=-2)], axis=-2)
        centres = 0.5 * (joints[..., 1:, :] + joints[..., :-1, :])
        return joints - centres.mean(axis=-2, keepdims=True)
    pts = np.stack([cum, np.zeros_like(cum)], axis=-1)
    return pts - pts.mean(axis=-2, keepdims=True)
