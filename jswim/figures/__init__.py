"""Figures of studies: the study figures (`plots`), their panels and curves, the wall and pair
studies' figures (`scenes`) and the shared style (`style`: widths, agent styles, rc settings).
"""

from jswim._exports import lazy_exports

#: Public name -> the module that defines it (loaded on first use).
_HOMES = {
    "study_figures": ".plots",
    "draw_figures": ".plots",
    "save": ".panels",
    "panel_keys": ".panels",
    "target_displacement": ".panels",
    "curves_figure": ".curves",
    "history_figure": ".curves",
    "grid_figure": ".grid",
    "noise_figure": ".grid",
    "inits_figure": ".grid",
    "ablation_figure": ".grid",
    "competence_figure": ".grid",
    "gaits_figure": ".sketches",
    "draw_cycle": ".sketches",
    "draw_shape": ".sketches",
    "learned_cycles": ".sketches",
    "shape_points": ".sketches",
    "signature_reference": ".curves",
    "wall_figures": ".scene_plots",
    "pair_figures": ".scene_plots",
    "school_figures": ".scene_plots",
    "RC": ".style",
    "AGENT_STYLE": ".style",
    "COLUMN_IN": ".style",
    "PAGE_IN": ".style",
    "tidy": ".style",
    "REFERENCE_STYLE": ".style",
    "NOTE_COLOR": ".style",
}

__all__ = list(_HOMES)

__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
