"""Old path of :mod:`jswim._io.interrupts` (moved in issue 30), kept so existing imports work."""

import sys

from jswim._io import interrupts as _moved

sys.modules[__name__] = _moved
