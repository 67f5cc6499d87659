"""Calibration, the stage after training: the hand-over rule chosen in the closed loop on held-out trials.

- :mod:`mpcshare.calibration.rule_choice` — :func:`~mpcshare.calibration.rule_choice.choose_for_bundle`:
  the wearer's modes and the hand-over settings of ``gate``, measured in the simulator, written into the bundle;
- :mod:`mpcshare.calibration.mode_cost` — what each mode costs under each party, and the order it prices;
- :mod:`mpcshare.calibration.trials` — which held-out trials the choice runs on, for how long, and which are left
  to evaluate it.

Training never imports this package; ``mpcshare train`` and ``mpcshare demo`` run it after training.
"""
