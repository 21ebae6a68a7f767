"""Old path of :mod:`jswim.judging.stats` (moved in issue 30), kept so existing imports work."""

import sys

from jswim.judging import stats as _moved

sys.modules[__name__] = _moved
