"""Old path of :mod:`jswim.judging.shape_judge` (moved in issue 30), kept so existing imports work."""

import sys

from jswim.judging import shape_judge as _moved

sys.modules[__name__] = _moved
