"""The reading order and the thresholds that every reader of study folders shares.

Tables (`jswim.studies.overview`), figures (`jswim.figures`), the report page and the bench's
leaderboard (`jswim.viz`, `jswim.bench`) read them here, from the layer that owns results, so
that no picture imports the code that runs a study.
"""

#: Reading order of swimmers in tables and figure panels (others follow, by name).
SWIMMER_ORDER = ("purcell", "ng", "nlink", "nsphere")
#: Reading order of agents in tables and figure panels (the LLM first; others follow, by name).
AGENT_ORDER = ("llm", "qlearning", "random", "ppo")
#: The agent that plays a fixed stroke (the scene studies' reference): it learns nothing, so its
#: rows say "fixed" where the others count the runs that learned.
STROKE_AGENT = "stroke"

#: Fewest runs that learned for which quartiles of the steps to learn are printed (below: the
#: median alone; quartiles of two values are interpolation, not data).
MIN_QUARTILE_N = 4
#: Fewest runs for which a bootstrap interval of X/a end is printed (two runs resample to three
#: values).
MIN_BOOTSTRAP_N = 3

__all__ = ["AGENT_ORDER", "MIN_BOOTSTRAP_N", "MIN_QUARTILE_N", "STROKE_AGENT", "SWIMMER_ORDER"]
