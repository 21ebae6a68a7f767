"""``python -m jswim``: the ``jswim`` command (the bench starts its studies this way).

A bench passes a study's arguments in the environment (``JSWIM_BENCH_ARGV``, a JSON list), never
on the command line, where any user of the machine could read a URL's password or a credential
given as a request field; the variable is dropped before the study starts.
"""

import json
import os
import sys

from jswim.cli import run

_given = os.environ.pop("JSWIM_BENCH_ARGV", None)
if _given is not None:
    sys.argv = [sys.argv[0], *json.loads(_given)]
run()
