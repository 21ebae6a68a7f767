"""Every model on the same bench (``jswim bench``).

- `jswim.bench.models_file`: the models file (TOML) and ``--model`` options;
- `jswim.bench.suites`: the suites (``core``, ``paper``, user-defined), their definitions;
- `jswim.bench.runner`: every model's studies at once, each in its own folder and process;
- `jswim.bench.leaderboard`: the leaderboard (table, CSV/JSON schema, figure).
"""

from jswim._exports import lazy_exports

#: Public name -> the module that defines it (loaded on first use).
_HOMES = {
    "ModelEntry": ".models_file",
    "ModelsFile": ".models_file",
    "load_models_file": ".models_file",
    "parse_model_option": ".models_file",
    "Suite": ".suites",
    "Part": ".suites",
    "SUITES": ".suites",
    "user_suite": ".suites",
    "run_jobs": ".runner",
    "plan": ".runner",
    "folder_rows": ".leaderboard",
    "table_text": ".leaderboard",
    "write_files": ".leaderboard",
}

__all__ = list(_HOMES)

__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
