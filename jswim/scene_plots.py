"""Old path of :mod:`jswim.figures.scenes` (moved in issue 30), kept so existing imports work."""

import sys

from jswim.figures import scenes as _moved

sys.modules[__name__] = _moved
