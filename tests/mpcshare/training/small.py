"""A small training configuration for the training tests (seconds, not minutes)."""

from mpcshare.training.config import TrainConfig

SMALL = TrainConfig(percentile=80, n_modes=3, hmm_restarts=1, max_epochs=3, patience=2,
                    gate_max_samples=200, seed=0)
