"""Old path of :mod:`jswim.figures.plots` (moved in issue 30), kept so existing imports work."""

import sys

from jswim.figures import plots as _moved

sys.modules[__name__] = _moved
