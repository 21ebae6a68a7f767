"""Judging a run: the success criterion (`gait`), the K-level ROC lattice (`lattice`), real-valued
strokes (`shape_judge`) and the statistics of steps to learn (`stats`)."""
