"""Old path of :mod:`jswim.judging.gait` (moved in issue 30), kept so existing imports work."""

import sys

from jswim.judging import gait as _moved

sys.modules[__name__] = _moved
