"""Old path of :mod:`jswim.figures.style` (moved in issue 30), kept so existing imports work."""

import sys

from jswim.figures import style as _moved

sys.modules[__name__] = _moved
