"""Causal signals of the robot's coming error, scored against its realised error (research, not installed).

:mod:`.signals`: the signal functions (windows, adaptive conformal quantiles, gamma dwell hazard, AUC);
:mod:`.record`: the robot alone and the wearer alone in the closed loop on held-out trials, with the
controller's internals per step; :mod:`.score`: labels, signals and their AUC table per world.
"""
