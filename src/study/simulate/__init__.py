"""Simulate: the MuJoCo scene, contact calibration, trajectory synthesis, the dataset file, physics checks
and measurements on trajectories."""
