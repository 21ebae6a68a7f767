"""What a run's protocol does differently from the paper and the authors' code.

The README's fidelity table lists every element; this module names, for one run's settings, the
deviations that apply, so each transcript and study folder records them next to the results.
Fixed ones (`ALWAYS`) are jswim's choices where the code is plainly an artefact or the
paper is followed over the code; the rest follow from the settings (`deviations`).
"""

from __future__ import annotations

from typing import Any

from jswim.agents.variants import LLMAgentConfig
from jswim.prompt import DEFAULT_TEMPLATE, PAPER_SYSTEM

#: Deviations of every run (paper over code, or the code's artefact replaced), one line each.
ALWAYS = (
    "physics: exact per-step displacements (closed-form RFT for Purcell, the NG formula) instead of the code's "
    "first-order time stepping (Purcell +x 0.19101, -x 0.19148 per cycle there; 0.19124724 both ways here)",
    "position: an integer, X truncated to 3 decimals (the paper) where the code prints a rounded float (2691.0)",
    "prompt wording: jswim's own sentences with the same elements and order (aliases, ranges, records with "
    "stuck flags, separate DOF and ROC choices)",
    "reply without a valid action: up to 2 corrective follow-ups, then the hold [1, 0] (the code re-sends the "
    "identical prompt up to 5 times, then [1, 0])",
)


def roc_levels_deviation(roc_levels: int) -> str | None:
    """The line of a ROC lattice finer than the paper's (``None`` for K = 1): an extension, the
    paper's first future direction (continuous actions)."""
    if roc_levels == 1:
        return None
    return (
        f"ROC on {roc_levels} levels (--roc-levels {roc_levels}, an extension): ROC k in -{roc_levels}..{roc_levels} "
        f"moves a DOF by k/{roc_levels} of its range per step (paper: -1, 0, 1, the whole range); S2 and S5 "
        "say so in one sentence each"
    )


#: The line of the real-valued RL baseline's action space (the continuous study).
REAL_ROCS = (
    "real-valued ROC in [-1, 1] (the continuous RL baseline, an extension): a step moves one DOF by ROC "
    "times its range, stopping at a limit; a cycle is a return to the same shape within 0.1 % of the range "
    "(jswim.judging.shape_judge.judge_shapes)"
)


def study_extensions(roc_levels: set[int] | list[int]) -> list[str]:
    """Lines for a study's metadata naming the extensions its runs use: each ROC lattice finer than
    the paper's, and real-valued ROCs (``roc_levels`` 0)."""
    out = [
        line for k in sorted(roc_levels) if k > 0 and (line := roc_levels_deviation(k)) is not None
    ]
    return out + ([REAL_ROCS] if 0 in roc_levels else [])


#: What a pair's prompt is under ``--pair-prompt each`` (a variant of the joint prompt).
EACH_PAIR_PROMPT = (
    "each swimmer steered by its own LLM conversation (--pair-prompt each, a variant of the joint "
    "prompt): swimmer 1 decides at odd steps, swimmer 2 at even ones, each with its own prompt about its "
    "arms D1, D2 and X, its own last n_ht records and clearing; records also show the other's position "
    "(other X, encoded as X); the reward is the progress of their mean"
)


def each_prompt(n: int) -> str:
    """What ``--pair-prompt each`` is for ``n`` >= 2 swimmers (`EACH_PAIR_PROMPT` for a pair)."""
    if n == 2:
        return EACH_PAIR_PROMPT
    return (
        "each swimmer steered by its own LLM conversation (--pair-prompt each, a variant of the joint prompt): "
        f"swimmer k decides at steps k, k + {n}, ..., each with its own prompt about its arms D1, D2 and X, its "
        f"own last n_ht records and clearing; records also show the others' positions (X1..X{n} but its own, "
        "encoded as X); the reward is the progress of their mean"
    )


def scene_deviation(scene: Any, pair_prompt: str = "joint") -> str:
    """The line of a run in a scene (an extension: the paper's swimmer is alone in an
    unbounded fluid), naming the medium, the swimmers (any number) and what the prompt shows
    (several swimmers': ``pair_prompt``, `jswim.agents.variants.PAIR_PROMPTS`)."""
    parts = [f"scene (an extension): medium {scene.medium!r}"]
    if scene.medium == "wall":
        parts.append(
            f"start {scene.height:g} a above a no-slip wall, tilt {scene.tilt:g} rad; records show each "
            "swimmer's height H (thousandths of a, as X) and tilt (rad)"
        )
    n = int(scene.swimmers)
    who = (
        f"two coaxial NG swimmers {scene.separation:g} a apart"
        if n == 2
        else f"{n} NG swimmers {scene.separation:g} a apart"
    )
    if n >= 2 and pair_prompt == "each":
        parts.append(f"{who}, {each_prompt(n)}")
    elif n >= 2:
        owns, xs = (
            ("swimmer 2 owns D3, D4", "X1 and X2")
            if n == 2
            else ("swimmer k owns D(2k-1), D(2k)", f"X1..X{n}")
        )
        parts.append(
            f"{who} steered through joint DOFs D1..D{2 * n} ({owns}); records show {xs}; the reward is the "
            "progress of their mean"
        )
    if scene.obstacles:
        parts.append(f"{len(scene.obstacles)} fixed spheres")
    return "; ".join(parts)


#: The line of the continuous RL baseline's rows in the scene studies.
SCENE_PPO = (
    "continuous RL baseline (PPO) on scenes (an extension): the continuous study's learner moves one arm of "
    "one swimmer per step by a real ROC (a pair: both swimmers, joint DOFs D1..D4); it observes the joint arms "
    "and, with a wall, each swimmer's height and tilt; reward = progress of the swimmers' mean x, the study's "
    "--steps and --q-runs; success = the shape judge on each swimmer's own moves with the bulk swimmer's "
    "displacements (a pair succeeds when both swimmers' own moves do)"
)


def scene_extensions(scenes: Any, ppo: bool = False) -> list[str]:
    """Lines for a study's metadata: one per distinct scene its runs use (none for the bulk fluid);
    an item may be a ``(scene, pair_prompt)`` pair. `SCENE_PPO` follows when the continuous RL
    baseline runs on them (``ppo``)."""
    lines = [scene_deviation(*s) if isinstance(s, tuple) else scene_deviation(s) for s in scenes]
    return lines + ([SCENE_PPO] if ppo and lines else [])


#: The line of a navigation run (an extension: the paper's task is swimming along x).
NAVIGATION = (
    "navigation task (an extension; docs/navigation.md): S1 names the target's position (X, Y), "
    "encoded as X is, with one X_min for both, lowered to a whole number of link lengths below "
    "every place the target can be; S2 adds what X, Y and the heading are and the success radius "
    "(a moving target: its velocity; a path: its number of waypoints); records give X, Y and the "
    "heading (rad) before and after each step; the run ends when the target is reached or at its "
    "step budget; the progress the clearing rule reads is the decrease of the distance to the target"
)


#: A navigation task in a background flow (an extension; docs/navigation.md, *Flows*).
FLOW = (
    "background flow (an extension; docs/navigation.md): the swimmer moves through a steady "
    "planar flow (resistive force theory for its links against the local fluid velocity); S2 says "
    "the fluid flows; each record gives the local flow (X, Y) at the centre before the step, in "
    "thousandths of a link length per step, truncated as the positions are; X_min is lowered below "
    "where the flow could carry the swimmer within the budget"
)


def flow_deviation(flow: str) -> str:
    """The line of a run in a background flow (canonical JSON of the flow): `FLOW` and the flow."""
    return f"{FLOW}; flow {flow}"


def navigation_deviation(target: str) -> str:
    """The line of a run with a navigation target (canonical JSON of its spec): `NAVIGATION`
    and the target."""
    return f"{NAVIGATION}; target {target}"


def deviations(
    cfg: LLMAgentConfig,
    *,
    temperature: float,
    constraint: str,
    max_tokens: int,
    default_max_tokens: int,
    n_ht: int | None = None,
    default_n_ht: int | None = None,
    roc_levels: int = 1,
) -> list[str]:
    """The deviations of one run with these settings from the paper's protocol (`ALWAYS` first).

    Parameters
    ----------
    cfg : LLMAgentConfig
        The agent settings.
    temperature : float
        The sampling temperature requests go out with.
    constraint : str
        The resolved constrained-decoding mode (``"none"`` in the paper).
    max_tokens, default_max_tokens : int
        The reply limit used and the swimmer's default (the code's).
    n_ht, default_n_ht : int, optional
        The history length used and the swimmer's default.
    roc_levels : int
        ``K`` of the run's ROC lattice (1: the paper's).
    """
    out = list(ALWAYS)
    if cfg.variant != "paper":
        out.append(f"protocol variant {cfg.variant!r} (not in the paper)")
    if cfg.order != "paper":
        out.append(
            f"sentence order {cfg.order!r}: S1 S2 S4 S5 before the history (paper: S1 S2 S3 S4 S5)"
        )
    if cfg.share_identical:
        out.append(
            "identical requests of different runs shared (--share-identical): runs from one start are copies, "
            "not independent repeats"
        )
    if constraint != "none":
        out.append(
            f"constrained decoding ({constraint}): replies can only be an offered action (paper: free text)"
        )
    if max_tokens != default_max_tokens:
        out.append(f"max_tokens {max_tokens} (code: {default_max_tokens})")
    if temperature != 0:
        out.append(f"temperature {temperature:g} (paper: 0)")
    if cfg.x_min != -2.5:
        out.append(f"X_min {cfg.x_min:g} (code: -2.5)")
    if cfg.system != PAPER_SYSTEM:
        out.append(f"system message {cfg.system!r} (code: a single space)")
    if cfg.template != DEFAULT_TEMPLATE:
        out.append("prompt template replaced (--prompt-file)")
    if cfg.clearing is not None:
        out.append(f"clearing rule: {cfg.clearing.describe()}")
    if n_ht is not None and default_n_ht is not None and n_ht != default_n_ht:
        out.append(f"n_ht {n_ht} (default {default_n_ht})")
    if (line := roc_levels_deviation(roc_levels)) is not None:
        out.append(line)
    return out


def describe_constraint(modes: Any) -> str:
    """One line for a study's output: whether its LLM replies were constrained."""
    modes = sorted({m for m in modes if m})
    if not modes:
        return ""
    if modes == ["none"]:
        return (
            "LLM replies: free text, parsed afterwards (no constrained decoding, as in the paper)"
        )
    return (
        f"LLM replies: constrained decoding ({', '.join(m for m in modes if m != 'none')}): the model could only "
        "answer with an offered action (the paper uses none; --constrain none for free text)"
    )
