"""Study grids (jswim.studies.specs, options, plans): fast, no runs are executed."""

from __future__ import annotations

from collections import Counter

import pytest

from jswim import cli, env
from jswim.agents.variants import VARIANTS, LLMRunSpec, run_id
from jswim.errors import ConfigError
from jswim.studies import COMPETENCE_VARIANTS, StudyOptions, build, get, names


@pytest.mark.parametrize(
    "study, total",
    [
        ("swim", 4 + 100 + 100),  # purcell, +x: 4 LLM runs, 100 Q-learners, 100 random
        ("curves", 2 * (1 + 100 + 100)),  # two swimmers
        ("history", 2 * 2 * 8 * 1),  # swimmers x directions x n_ht 1..8 x 1 run
        ("noise", 2 * 7 * (10 + 100 + 100)),  # swimmers x 7 noise levels x (LLM + baselines)
        ("ablation", 2 * 6 * 10),  # swimmers x (full + 5 sentences dropped) x 10
        ("inits", 2 * 2 * 4 * 1),  # swimmers x directions x 4 corners
        (
            "competence",
            2 * (7 * 10 + 2 * 2 * 100),
        ),  # 7 variants x 10, 2 baselines x 2 action sets x 100
    ],
)
def test_default_grid_sizes(study, total):
    assert len(build(study, StudyOptions())) == total


def test_the_table_holds_each_study_s_defaults():
    assert set(names()) == {
        "curves",
        "history",
        "noise",
        "ablation",
        "inits",
        "swim",
        "competence",
        "temperature",
        "continuous",
        "wall",
        "pair",
        "school",
        "navigate",
    }
    for study, spec in ((n, get(n)) for n in names()):
        plans = build(study, StudyOptions())
        assert {p.swimmer for p in plans} == set(spec.swimmers)
        assert {p.direction for p in plans} == set(spec.directions)
        per_cell = Counter((p.agent, p.swimmer, p.direction, p.group) for p in plans)
        assert {n for (a, *_), n in per_cell.items() if a == "llm"} <= {spec.runs}
        assert {
            n
            for (a, *_), n in per_cell.items()
            if a not in ("llm", "stroke", "controller", "optimal", "mpc", "zermelo")
        } <= {spec.q_runs}
        assert {
            n
            for (a, *_), n in per_cell.items()
            if a in ("stroke", "controller", "optimal", "mpc", "zermelo")
        } <= {1}  # deterministic without noise
    # Options override the table.
    plans = build("noise", StudyOptions(swimmers=("ng",), runs=2, q_runs=0, zetas=(0.0, 1.0)))
    assert Counter(p.group for p in plans) == {"zeta=0": 2, "zeta=1": 2} and {
        p.zeta for p in plans
    } == {0.0, 1.0}


def test_run_ids_and_seeds_keep_their_historic_form():
    # Existing study folders are matched by these ids: their format may not drift.
    swim = build("swim", StudyOptions(runs=2, q_runs=1, seed=3))
    assert [p.run_id for p in swim] == [
        "llm-purcell-px-i++-z0-r0",
        "llm-purcell-px-i++-z0-r1",
        "qlearning-purcell-px-i++-z0-r0",
        "random-purcell-px-i++-z0-r0",
    ]
    # Seeds: a hash of the study seed and the run id (pinned: a drift would change every folder's
    # remaining runs); their properties are tested in test_paid_api.
    assert [p.seed for p in swim] == [386529587, 1553550097, 312050790, 696737300]
    abl = build("ablation", StudyOptions(swimmers=("ng",), runs=1, n_ht=3))
    assert [p.run_id for p in abl][:2] == ["llm-ng-px-i++-z0-h3-r0", "llm-ng-px-i++-z0-h3-noS1-r0"]
    comp = build(
        "competence", StudyOptions(swimmers=("purcell",), runs=1, q_runs=1, variants=("shuffle",))
    )
    assert [p.run_id for p in comp] == [
        "llm-purcell-px-i++-z0-shuffle-r0",
        "random-purcell-px-i++-z0-r0",
        "random-purcell-px-i++-z0-shape-changing-r0",
        "qlearning-purcell-px-i++-z0-r0",
        "qlearning-purcell-px-i++-z0-shape-changing-r0",
    ]
    # One builder: a spec without a run id gets one of the same form, with its seed.
    assert (
        LLMRunSpec("ng", direction=-1, init="+-", zeta=0.5, seed=7, n_ht=6).label()
        == "llm-ng-mx-i+--z0.5-h6-s7"
    )
    assert (
        run_id("random", "purcell", 1, (0, 1), 0.0, tag="shape-changing", repeat=2)
        == "random-purcell-px-i-+-z0-shape-changing-r2"
    )


def test_bad_options_are_refused():
    with pytest.raises(ConfigError, match="unknown study"):
        build("fig6", StudyOptions())
    for bad in (
        dict(swimmers=("squid",)),
        dict(action_set="some"),
        dict(steps=0),
        dict(zetas=(-1.0,)),
        dict(init="sideways"),
        dict(variant="oracle"),
    ):
        with pytest.raises(ConfigError):
            StudyOptions(**bad)


def test_the_old_allowed_flag_still_parses_as_action_set():
    args = cli.build_parser().parse_args(["swim", "--allowed", "shape-changing"])
    assert args.action_set == "shape-changing"
    assert (
        cli.build_parser().parse_args(["study", "noise", "--action-set", "all"]).action_set == "all"
    )


def test_competence_grid():
    plans = build("competence", StudyOptions())
    llm = [p for p in plans if p.agent == "llm"]
    counts = Counter((p.swimmer, p.variant) for p in llm)
    assert counts == {(sw, v): 10 for sw in ("purcell", "ng") for v in COMPETENCE_VARIANTS}
    assert all(p.steps == 50 and p.direction == 1 and p.group == p.variant for p in llm)
    assert all(p.action_set == VARIANTS[p.variant].get("action_set", "all") for p in llm)
    # Starts go through the four corners.
    inits = [p.init for p in llm if p.swimmer == "ng" and p.variant == "paper"]
    assert inits[:4] == list(env.all_inits(2)) and inits[4] == inits[0]
    base = Counter((p.agent, p.swimmer, p.action_set, p.group) for p in plans if p.agent != "llm")
    assert base == {
        (a, sw, s, s): 100
        for a in ("random", "qlearning")
        for sw in ("purcell", "ng")
        for s in ("all", "shape-changing")
    }
    assert len({p.seed for p in plans}) == len(plans) and len({p.run_id for p in plans}) == len(
        plans
    )
    picked = build("competence", StudyOptions(variants=("shuffle",), runs=3, q_runs=0))
    assert [p.variant for p in picked] == ["shuffle"] * 6
    # Elsewhere a variant applies to every LLM run, and its allowed set to the baselines.
    swim = build("swim", StudyOptions(variant="shape-changing+shuffle", q_runs=2))
    assert {(p.agent, p.action_set, p.variant) for p in swim} == {
        ("llm", "shape-changing", "shape-changing+shuffle"),
        ("qlearning", "shape-changing", ""),
        ("random", "shape-changing", ""),
    }
    assert {p.variant for p in build("ablation", StudyOptions(runs=1))} == {"paper"}
    assert get("ablation").variant == "paper"


@pytest.mark.parametrize("seed", [4295, -1, 2**70])
def test_any_integer_seed_gives_32_bit_run_seeds(seed):
    from jswim.env import seed32, seed_key

    plans = build("swim", StudyOptions(runs=2, q_runs=1, seed=seed))
    assert all(0 <= p.seed < 2**32 for p in plans) and len({p.seed for p in plans}) == len(plans)
    assert [p.seed for p in build("swim", StudyOptions(runs=2, q_runs=1, seed=seed))] == [
        p.seed for p in plans
    ]
    assert seed32(12345) == 12345 and seed32(-1) != seed32(-2) and seed_key(2**70).shape == (2,)


def test_the_continuous_study_grid():
    from jswim.studies.options import continuous_agent_available

    plans = build("continuous", StudyOptions(runs=1, q_runs=2, roc_levels_grid=(1, 5)))
    cells = Counter((p.agent, p.group, p.roc_levels) for p in plans)
    # Per swimmer and direction: each lattice for the LLM and both baselines, the real-valued RL once.
    real = {("ppo", "continuous", 0): 8} if continuous_agent_available() else {}
    assert cells == {
        ("llm", "K=1", 1): 4,
        ("qlearning", "K=1", 1): 8,
        ("random", "K=1", 1): 8,
        ("llm", "K=5", 5): 4,
        ("qlearning", "K=5", 5): 8,
        ("random", "K=5", 5): 8,
        **real,
    }
    ids = {p.run_id for p in plans}
    # K = 1 runs keep the paper's ids; finer lattices and real ROCs are named.
    assert {
        "llm-ng-mx-i+--z0-r0",
        "llm-ng-mx-i+--z0-K5-r0",
        "qlearning-purcell-px-i++-z0-K5-r1",
    } <= ids
    assert ("ppo-purcell-px-i++-z0-real-r0" in ids) == continuous_agent_available()
    # One K on any other study: every run of the swim study on the K = 2 lattice.
    swim = build("swim", StudyOptions(runs=1, q_runs=1, roc_levels=2))
    assert [p.run_id for p in swim] == [
        "llm-purcell-px-i++-z0-K2-r0",
        "qlearning-purcell-px-i++-z0-K2-r0",
        "random-purcell-px-i++-z0-K2-r0",
    ]
    assert {p.roc_levels for p in swim} == {2}
