"""Figures of studies: the study figures (`plots`), the wall and pair studies' figures (`scenes`)
and the shared style (`style`: widths, agent styles, rc settings)."""
