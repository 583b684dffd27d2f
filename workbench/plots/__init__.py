"""Matplotlib figures: joint trajectories, the arm in 3D."""
