"""Every model on the same bench (``jswim bench``).

- :mod:`jswim.bench.models`: the models file (TOML) and ``--model`` options;
- :mod:`jswim.bench.suites`: the suites (``core``, ``paper``, user-defined), their definitions;
- :mod:`jswim.bench.runner`: every model's studies at once, each in its own folder and process;
- :mod:`jswim.bench.leaderboard`: the leaderboard (table, CSV/JSON schema, figure).
"""
