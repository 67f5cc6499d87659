"""The reactive predictor's default settings, written once.

:class:`learning.predictor.lstm.ReactivePredictor`'s signature and
``mpcshare.training.TrainConfig`` both read them here (this module imports nothing, so
settings and the command line read them without importing torch).
"""

from __future__ import annotations

__all__ = ["BATCH_SIZE", "BURN_IN", "CHUNK_LEN", "HIDDEN_SIZE", "LEARNING_RATE", "MAX_EPOCHS", "NUM_THREADS",
           "PATIENCE", "VAL_FRACTION"]

#: LSTM units (Song & Asada: 28)
HIDDEN_SIZE: int = 28
#: chunks per gradient step (Song & Asada: 64)
BATCH_SIZE: int = 64
#: steps per training chunk that carry loss: short chunks give more gradient steps per epoch at
#: about the same cost (default data: chunks of 25 reach a lower validation loss than chunks of
#: 100 in less time)
CHUNK_LEN: int = 25
#: earlier steps prepended to a chunk to warm the state (no loss)
BURN_IN: int = 20
#: Adam's learning rate
LEARNING_RATE: float = 1e-2
#: epochs at most; early stopping ends training after PATIENCE epochs without a validation improvement
MAX_EPOCHS: int = 80
PATIENCE: int = 10
#: share of the training trials held out for early stopping
VAL_FRACTION: float = 0.2
#: torch CPU threads while training: the network is small, and on a busy 2-core machine two
#: threads were many times slower than one (427 s against 24.5 s, 18k steps, 150 epochs)
NUM_THREADS: int = 1
