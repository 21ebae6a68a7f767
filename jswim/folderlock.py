"""Old path of :mod:`jswim._io.folderlock` (moved in issue 30), kept so existing imports work."""

import sys

from jswim._io import folderlock as _moved

sys.modules[__name__] = _moved
