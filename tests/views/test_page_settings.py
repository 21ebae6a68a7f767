"""The report page's settings block says what the study ran, in the study's own terms."""

from __future__ import annotations

from jswim.studies.options import COMPETENCE_VARIANTS
from jswim.viz.page import applicable_settings


def _meta(study: str, **extra):
    return {
        "study": study,
        "identity": {"options": {"action_set": "all", "steps": 20, "seed": 0}},
        **extra,
    }


def test_competence_settings_name_its_variants_and_whose_action_set_is_whose():
    meta = _meta("competence", llm_variants=list(COMPETENCE_VARIANTS))
    settings = dict(applicable_settings(meta))
    assert settings["llm_variants"] == ", ".join(COMPETENCE_VARIANTS)
    # not a bare "all": the shape-changing variants and the baselines' second set ran too
    assert settings["action_set"] != "all" and "shape-changing variants" in settings["action_set"]


def test_other_studies_keep_the_bare_action_set_and_list_no_variants():
    settings = dict(applicable_settings(_meta("curves", llm_variants=["paper"])))
    assert settings["action_set"] == "all" and "llm_variants" not in settings


def test_continuous_settings_give_the_k_levels_once_and_name_ppo_s_real_rocs():
    meta = _meta("continuous", roc_levels=[0, 1, 2, 5, 10], grid={"roc_levels_grid": [1, 2, 5, 10]})
    settings = applicable_settings(meta)
    names = [k for k, _ in settings]
    assert names.count("roc_levels") == 1 and "roc_levels_grid" not in names
    assert dict(settings)["roc_levels"] == "1, 2, 5, 10; real-valued ROCs (PPO)"


def test_a_school_page_names_no_model_and_no_prompt_or_move_settings():
    meta = _meta("school", grid={"school_sizes": [1, 2], "runs": None})
    meta["identity"]["backend"] = {"model": "SmolLM2", "kind": "embedded"}
    meta["identity"]["options"].update(x_min=-2.5, zeta=0.0)
    names = [k for k, _ in applicable_settings(meta)]
    assert "model" not in names and "action_set" not in names and "x_min" not in names
    assert "zeta" in names and "school_sizes" in names


def test_a_temperature_sweep_s_page_does_not_give_the_backend_s_temperature_as_the_runs():
    meta = _meta("temperature", grid={"roc_levels_grid": [1, 2, 5, 10]})
    meta["identity"]["backend"] = {"model": "m", "kind": "remote", "temperature": 0.0}
    settings = dict(applicable_settings(meta))
    assert "temperature per run" in settings["model"] and "temperature 0.0" not in settings["model"]
    assert settings["temperatures"] == "0, 0.25, 0.5, 0.75, 1"
    assert "roc_levels_grid" not in settings  # only the continuous study sweeps K


def test_seeded_starts_show_on_a_navigation_page_only():
    nav = dict(applicable_settings(_meta("navigate", grid={"starts": 4, "distances": [3.0]})))
    assert nav["starts"] == "4"
    curves = dict(applicable_settings(_meta("curves", grid={"starts": 1})))
    assert "starts" not in curves
