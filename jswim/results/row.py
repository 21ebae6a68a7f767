"""One run of a study as a typed row ([`RunRow`][jswim.results.row.RunRow]): its columns and their order.

Rows are built in one place ([`jswim.studies.rows.build_row`][jswim.studies.rows.build_row]) and written by
[`jswim.results.StudyStore.add_runs`][jswim.results.StudyStore.add_runs]; [`jswim.results.read_runs`][jswim.results.read_runs] gives them back as
plain dicts, in today's form ([`jswim.results.migrate.migrate_row`][jswim.results.migrate.migrate_row]), for users;
the package's readers read [`jswim.results.read_run_rows`][jswim.results.read_run_rows] (typed rows) and convert rows given
to them with [`as_run_rows`][jswim.results.row.as_run_rows].
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any
from collections.abc import Iterable, Iterator

from jswim.results.migrate import migrate_row
from jswim.results.optimum import with_cell_optimum

#: The columns every row starts with, in their order.
HEAD = (
    "run_id",
    "agent",
    "swimmer",
    "direction",
    "init",
    "zeta",
    "seed",
    "n_ht",
    "drop",
    "action_set",
    "group",
    "variant",
    "steps",
    "final_x",
    "signed_final_x",
    "success",
    "learned",
    "steps_to_learn",
    "period",
    "roc_levels",
)
#: A scene run's own columns (None in the paper's world), after `HEAD`.
SCENE = (
    "scene",
    "medium",
    "n_swimmers",
    "start_height",
    "separation",
    "fate",
    "mean_height",
    "speed",
    "per_cycle",
    "plane_height",
)
#: A scene run's per-step, per-swimmer tracks.
TRACKS = ("xs", "heights", "tilts", "contact")
#: An LLM run's calls and replies (None for the other agents).
USAGE = (
    "error",
    "failed_steps",
    "parse_retries",
    "truncated",
    "cut_thinking",
    "reasoning_tokens",
    "http_retries",
    "n_clears",
    "calls",
    "billed_calls",
    "cache_hits",
    "prompt_tokens",
    "completion_tokens",
    "cached_tokens",
    "cost_usd",
    "tokens_seen",
    "replayed_calls",
)

#: The LLM agent's switches ([`jswim.agents.variants.LLMAgentConfig.knobs`][jswim.agents.variants.LLMAgentConfig.knobs] and what the
#: driver adds); the last two are written only where set.
SWITCHES = (
    "summary",
    "shuffle",
    "temperature",
    "order",
    "share_identical",
    "constraint",
    "max_tokens",
    "pair_prompt",
    "temperature_sent",
)
#: A navigation run's columns (docs/navigation.md): written only where set (a navigation task).
NAV = ("target", "reached", "steps_to_target", "path_length", "path_ratio")
#: A navigation run in a background flow (docs/navigation.md, *Flows*): written only where set.
FLOW = (
    "flow",
    "flow_fraction",
    "reachable",
    "zermelo_steps",
    "zermelo_ratio",
    "optimal_steps",
    "time_ratio",
)

_WHERE_SET = ("pair_prompt", "temperature_sent", "plane_height") + NAV + FLOW

#: A run's energy columns (None where its world does not count work, and in older folders).
ENERGY = ("energy", "energy_per_distance", "efficiency")

#: The four layouts of a row (bulk or scene world, LLM or not), as written since the columns
#: existed; ``other`` is where columns this version does not know go. A layout's order is the
#: in-memory order; ``runs.jsonl`` sorts its keys.
LAYOUTS = {
    (False, False): HEAD
    + ("sample", "x", "actions", "progress")
    + ENERGY
    + NAV
    + FLOW
    + ("status", "y", "orientation", "other"),
    (False, True): HEAD
    + ("sample", "x", "actions", "progress")
    + ENERGY
    + NAV
    + FLOW
    + ("status",)
    + USAGE
    + ("y", "orientation", "below_x_min")
    + SWITCHES
    + ("other",),
    (True, False): HEAD
    + SCENE
    + ("x", "y", "orientation", "actions", "progress")
    + ENERGY
    + ("status",)
    + TRACKS
    + ("stuck", "other"),
    (True, True): HEAD
    + SCENE
    + ("x", "y", "orientation", "actions", "progress")
    + ENERGY
    + ("status",)
    + USAGE
    + ("stuck", "below_x_min")
    + SWITCHES
    + ("other",)
    + TRACKS,
}


@dataclass(frozen=True, eq=False)
class RunRow(Mapping):
    """One finished (or failed) run of a study: the record ``runs.jsonl`` holds per line.

    Lengths in sphere radii ``a`` (Purcell: its link length), angles in radians, steps counted
    from 1; series hold one value per executed step (the state after it). Readers may index a
    row by column name (``row["final_x"]``, ``row.get("cost_usd")``: a read-only
    `Mapping` of [`to_dict`][jswim.results.row.RunRow.to_dict]), so code written for the dict rows that
    [`read_runs`][jswim.results.read_runs] returns takes a fresh row as well, and users' notebooks that
    index rows keep working; new code reads attributes.

    Attributes
    ----------
    run_id : str
        The run's id in its study (``<group>-<agent>-...``; ``-sample<k>`` for repeats).
    agent : str
        ``"llm"``, ``"qlearning"``, ``"random"``, ``"ppo"`` (real-valued ROCs) or ``"stroke"``.
    swimmer : str
        ``"purcell"`` or ``"ng"``.
    direction : int
        Target direction along x, +1 or -1.
    init : str
        Start: one ``+``/``-`` per DOF (at its upper or lower bound), or the plan's text (scenes).
    zeta : float
        Noise level of the run (dimensionless, the paper's zeta).
    seed : int
        The run's seed (from the study seed and its id).
    n_ht : int or None
        History length shown to the LLM (None for the other agents).
    drop : str
        Prompt sentences left out (``"S1,S3"``; ``""``: none).
    action_set : str
        The actions offered (``"all"`` or the set's name).
    group : str
        The cell of the study's grid the run belongs to (``"n_ht=3"``, ``"h=3"``, ...).
    variant : str
        LLM protocol variant (`jswim.agents.variants.VARIANTS`; ``""`` for baselines).
    steps : int
        Steps executed.
    final_x : float
        Centroid x after the last step (a; a scene: the swimmers' mean).
    signed_final_x : float
        ``direction * final_x``: the displacement in the target direction.
    success, learned : bool
        The study's success criterion ([`jswim.judging.gait.judge`][jswim.judging.gait.judge]), and whether the run
        ends on a qualifying stroke.
    steps_to_learn : int or None
        The step at which the final qualifying stroke starts (None unless learned).
    period : int
        Period of the final stroke in steps (0: none; a pair's rows: 0).
    roc_levels : int
        K of the ROC lattice (1: the paper's; 0: real ROCs).
    sample : int or None
        Which repeat of its setting (``--samples``); paper's world only (None in scene rows).
    x, progress : list of float
        Centroid x after each step (a), and each step's displacement in the target direction (a).
    energy : float or None
        The run's total work on the fluid, the sum of its steps'
        [`StepInfo.work`][jswim.env.base.StepInfo] (``xi_par a^3 / tau`` for Purcell's swimmer,
        ``6 pi mu a^3 / tau`` for NG). None where the world does not count work (scenes) and in
        folders written before the column existed.
    energy_per_distance : float or None
        ``energy / |final_x|`` (the work per unit distance along x; None when the run ends at
        ``x = 0``).
    efficiency : float or None
        Lighthill's efficiency of the whole run, ``C X^2 / (N W)``: the power of towing the
        rigid swimmer at the run's mean speed ``X / (N tau)`` over the mean power ``W / (N tau)``
        the strokes spent, ``C`` the straight swimmer's axial drag (one unit per link or sphere;
        [`jswim.env.work.lighthill_efficiency`][jswim.env.work.lighthill_efficiency],
        docs/physics.md, *Energy and turning*). None when ``energy`` is None or 0.
    actions : list of list
        Each step's ``[dof, roc]`` (ROC in -1, 0, 1, or a real ROC for ``ppo``).
    status : str
        ``"done"``, ``"below_x_min"``, or a failure (`jswim.results.schema.FAILED_STATUSES`).
    y, orientation : list of float or None
        Centroid y (a) and orientation (rad) after each step; a scene: swimmer 1's height above
        the wall and tilt.
    scene : str or None
        Canonical JSON of the run's [`jswim.scenes.Scene`][jswim.scenes.scene.Scene]; None (and every scene column
        None) in the paper's world.
    medium : str or None
        ``"wall"`` or ``"free"``.
    n_swimmers : int or None
        Swimmers in the scene.
    start_height : float or None
        Swimmer 1's middle-sphere height above the wall at the start (a; wall scenes).
    separation : float or None
        Distance D between the swimmers at the start (a; several swimmers).
    fate : str or None
        A wall run's fate (`jswim.studies.scene_studies.FATES`).
    mean_height : float or None
        Mean height of the run's second half (a; wall scenes).
    speed : float or None
        Mean progress per step over the second half, in whole stroke cycles (a per step).
    per_cycle : float or None
        A stroke run's displacement per stroke cycle (a; strokes only).
    plane_height : float or None
        The height (link lengths) above a wall of the plane a planar swimmer swims in, parallel
        to the wall (the world's [`Scenery.plane_height`][jswim.env.base.Scenery]): its pictures
        are drawn from above, in that plane, and ``y``/``orientation`` are in the plane. Written
        only when set; rows written before the column existed get it by the old rule
        ([`migrate_row`][jswim.results.migrate.migrate_row]).
    xs, heights, tilts : list of list of float or None
        Per step, each swimmer's displacement (a), height (a) and tilt (rad).
    contact, stuck : list of bool or None
        Per step, whether a sphere touched the wall, and whether a swimmer was stuck.
    error : str or None
        The server's error of a failed LLM run.
    failed_steps, parse_retries, truncated, cut_thinking, n_clears : int or None
        LLM steps without a valid action, follow-ups asked, replies cut at ``max_tokens``, of those
        cut while reasoning, history clears.
    reasoning_tokens, prompt_tokens, completion_tokens, cached_tokens, tokens_seen : int or None
        Tokens the server reported (``tokens_seen``: of every call, cached and shared ones too).
    http_retries, calls, billed_calls, cache_hits, replayed_calls : int or None
        Retries, chat calls, calls billed, answered from the disk cache, replayed from the journal.
    cost_usd : float or None
        What the run's calls cost (USD).
    below_x_min : int or None
        First step whose x fell below ``x_min`` (LLM runs).
    summary, shuffle, share_identical : bool or None
        The LLM agent's switches ([`jswim.agents.variants.LLMAgentConfig`][jswim.agents.variants.LLMAgentConfig]).
    temperature : float or None
        The sampling temperature the agent asked for.
    order : str or None
        The order of the prompt's options (``"paper"`` or ``"cache"``).
    constraint : str or None
        Constrained decoding used: ``"grammar"``, ``"json_schema"``, ``"json_object"`` or ``"none"``.
    max_tokens : int or None
        The reply budget sent per call (None: none sent).
    pair_prompt : str or None
        Several swimmers: one joint conversation (``"joint"``) or one per swimmer (``"each"``);
        written only where set.
    temperature_sent : float or None
        The temperature the requests carried where the server's model refused the agent's;
        written only where set.
    target : str or None
        A navigation run's target (canonical JSON of the spec's ``to_dict()``,
        [`jswim.env.targets`][jswim.env.targets]); this and the next four are written only for
        navigation runs (docs/navigation.md).
    reached : bool or None
        The target (a path's last waypoint) was reached within the budget: the run's success.
    steps_to_target : int or None
        Steps until it was reached (None: not reached).
    path_length : float or None
        Length of the centroid's path over the run (``a``, the sum of its steps' displacements).
    path_ratio : float or None
        ``path_length`` over the straight distance of the task (the polyline from the start
        through the waypoints, the last one where the target was when reached); None when not
        reached.
    flow : str or None
        A navigation run's background flow (canonical JSON of the flow's ``to_dict()``,
        [`jswim.env.flows`][jswim.env.flows]); this and the next four are written only for runs
        in a flow.
    flow_fraction : float or None
        The flow's speed over the swimming speed
        (`SWIM_SPEED` in [`jswim.env.flows`][jswim.env.flows]).
    reachable : bool or None
        Zermelo's point steerer with the swimming speed reaches the target in this flow
        ([`jswim.agents.zermelo`][jswim.agents.zermelo]); False: no agent can, the row says so.
    zermelo_steps : float or None
        Zermelo's least time to the target (steps, ``tau``); None when unreachable.
    zermelo_ratio : float or None
        ``steps_to_target / zermelo_steps`` (None: not reached, or unreachable). An earlier
        jswim's ``time_ratio`` was this ([`migrate_row`][jswim.results.migrate.migrate_row]).
    optimal_steps : int or None
        The swimmer's own least time to the target (steps, the least-time sequence of the world's
        actions, [`jswim.agents.optimal`][jswim.agents.optimal]), in still fluid too; None where
        the search found none within the budget. Written on the cell's ``optimal`` row; every
        other row of the cell reads it from there
        ([`with_cell_optimum`][jswim.results.optimum.with_cell_optimum]).
    time_ratio : float or None
        ``steps_to_target / optimal_steps`` (None: not reached, or no optimum), read as
        ``optimal_steps`` is.
    other : Mapping
        Any column this version does not know (a folder written by another one), in its order.
    """

    run_id: str
    agent: str
    swimmer: str
    direction: int
    init: str
    zeta: float
    seed: int
    n_ht: int | None
    drop: str
    action_set: str
    group: str
    variant: str
    steps: int
    final_x: float
    signed_final_x: float
    success: bool
    learned: bool
    steps_to_learn: int | None
    period: int
    roc_levels: int
    x: list[float]
    actions: list[list[float]]
    progress: list[float]
    status: str = "done"
    sample: int | None = None
    y: list[float] | None = None
    orientation: list[float] | None = None
    scene: str | None = None
    medium: str | None = None
    n_swimmers: int | None = None
    start_height: float | None = None
    separation: float | None = None
    fate: str | None = None
    mean_height: float | None = None
    speed: float | None = None
    per_cycle: float | None = None
    plane_height: float | None = None
    xs: list[list[float]] | None = None
    heights: list[list[float]] | None = None
    tilts: list[list[float]] | None = None
    contact: list[bool] | None = None
    stuck: list[bool] | None = None
    error: str | None = None
    failed_steps: int | None = None
    parse_retries: int | None = None
    truncated: int | None = None
    cut_thinking: int | None = None
    reasoning_tokens: int | None = None
    http_retries: int | None = None
    n_clears: int | None = None
    calls: int | None = None
    billed_calls: int | None = None
    cache_hits: int | None = None
    prompt_tokens: int | None = None
    completion_tokens: int | None = None
    cached_tokens: int | None = None
    cost_usd: float | None = None
    tokens_seen: int | None = None
    replayed_calls: int | None = None
    below_x_min: int | None = None
    summary: bool | None = None
    shuffle: bool | None = None
    temperature: float | None = None
    order: str | None = None
    share_identical: bool | None = None
    constraint: str | None = None
    max_tokens: int | None = None
    energy: float | None = None
    energy_per_distance: float | None = None
    efficiency: float | None = None
    pair_prompt: str | None = None
    temperature_sent: float | None = None
    target: str | None = None
    reached: bool | None = None
    steps_to_target: int | None = None
    path_length: float | None = None
    path_ratio: float | None = None
    flow: str | None = None
    flow_fraction: float | None = None
    reachable: bool | None = None
    zermelo_steps: float | None = None
    zermelo_ratio: float | None = None
    optimal_steps: int | None = None
    time_ratio: float | None = None
    other: Mapping[str, Any] = field(default_factory=dict)

    def columns(self) -> tuple[str, ...]:
        """The row's column names in order (its layout, the unknown columns in place)."""
        other = tuple(k for k in self.other if k not in _FIELDS)
        return tuple(
            c
            for k in LAYOUTS[self._kind]
            for c in (other if k == "other" else (k,))
            if c not in _WHERE_SET or getattr(self, c) is not None
        )

    @property
    def _kind(self) -> tuple[bool, bool]:
        """(a scene's row, an LLM run's row): the key of its layout in `LAYOUTS`."""
        return self.medium is not None, self.agent == "llm"

    def to_dict(self) -> dict[str, Any]:
        """The record ``runs.jsonl`` holds: the columns of the row's layout, in order."""
        return {k: self[k] for k in self.columns()}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> RunRow:
        """A row from a record (any version's, in today's form by
        [`migrate_row`][jswim.results.migrate.migrate_row]: missing columns None, unknown ones
        kept in `other`; a missing or null ``group`` or ``agent`` reads as ``""``, ``x`` as
        ``[]``, ``steps`` as the length of ``x``)."""
        d = migrate_row(d)
        # The columns every reader sorts, sums or draws by, where a record lacks them (a hand
        # edit, a foreign writer): no cell ("", a study without a grid), no agent, no steps.
        x = d.get("x") if isinstance(d.get("x"), list) else []
        unset = {"group": "", "agent": "", "x": x, "steps": len(x)}
        d.update({k: v for k, v in unset.items() if d.get(k) is None})
        return cls(
            **{k: d.get(k) for k in _FIELDS}, other={k: v for k, v in d.items() if k not in _FIELDS}
        )

    def __getitem__(self, key: str) -> Any:
        if key in _FIELDS:
            if key not in _IN_LAYOUT[self._kind] or (
                key in _WHERE_SET and getattr(self, key) is None
            ):
                raise KeyError(
                    key
                )  # a column of another layout (a bulk row's scene), or one not set
            return getattr(self, key)
        return self.other[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.columns())

    def __len__(self) -> int:
        return len(self.columns())


_FIELDS = frozenset(f.name for f in dataclasses.fields(RunRow)) - {"other"}
_IN_LAYOUT = {kind: frozenset(cols) - {"other"} for kind, cols in LAYOUTS.items()}


def as_run_row(row: Mapping[str, Any]) -> RunRow:
    """``row`` as a [`RunRow`][jswim.results.row.RunRow]: a RunRow passes through, a dict goes through
    [`RunRow.from_dict`][jswim.results.row.RunRow.from_dict] (an earlier version's record migrated, missing columns None, unknown ones in
    `RunRow.other`)."""
    return row if isinstance(row, RunRow) else RunRow.from_dict(row)


def as_run_rows(rows: Iterable[Mapping[str, Any]]) -> list[RunRow]:
    """``rows`` as [`RunRow`][jswim.results.row.RunRow] objects: the one entry point of readers given rows by users.

    Parameters
    ----------
    rows : iterable of Mapping
        Run records: [`RunRow`][jswim.results.row.RunRow] objects (passed through unchanged) or dicts, such as
        [`jswim.results.read_runs`][jswim.results.read_runs] returns or a notebook builds ([`as_run_row`][jswim.results.row.as_run_row]).

    Returns
    -------
    list of RunRow
        One row per record, in order; a navigation row's optimum columns are its cell's
        ``optimal`` row's where ``rows`` hold it
        ([`with_cell_optimum`][jswim.results.optimum.with_cell_optimum]).
    """
    return with_cell_optimum([as_run_row(r) for r in rows])
