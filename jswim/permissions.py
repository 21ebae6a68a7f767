"""Old path of :mod:`jswim._io.permissions` (moved in issue 30), kept so existing imports work."""

import sys

from jswim._io import permissions as _moved

sys.modules[__name__] = _moved
