"""Physics, pure JAX: a swimmer's shape and its rates give its body-frame velocities.

The paper's closed forms (`purcell`, `ng`), Purcell-type chains (`nlink`), sphere swimmers
(`nsphere`), the mobility of spheres (`mobility`), force-free solves (`forcefree`, `bodyframe`),
Purcell's swimmer above a wall (`wall_rft`) and body outlines (`outline`); `models` names the
swimmers (`make_model`).
"""

from jswim._exports import lazy_exports

#: Public name -> the module that defines it (loaded on first use).
_HOMES = {
    "SWIMMERS": ".models",
    "SwimmerModel": ".models",
    "make_model": ".models",
    "RigidMotion": ".forcefree",
    "solve": ".forcefree",
    "rigid_motion": ".forcefree",
    "MOBILITIES": ".mobility",
    "mobility_matrix": ".mobility",
    "WallPurcellModel": ".wall_rft",
    "wall_model": ".wall_rft",
}

__all__ = list(_HOMES)

__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
