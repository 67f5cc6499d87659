"""The online shared controller, every 10 ms.

- :mod:`mpcshare.control.controller` — :class:`SharedController` (``step`` never raises);
- :mod:`mpcshare.control.types` — its output :class:`ControlCommand`, :class:`ControllerConfig`
  and the ranked status names;
- :mod:`mpcshare.control.frontend` — the streaming front end (Kalman filter, anti-aliased
  history, model ticks) and the controller's sensing stage (``sense``);
- :mod:`mpcshare.control.models_tick` — the learned parts of a step: the gate and the streaming
  predictor on a model tick, the control-rate forecast every step;
- :mod:`mpcshare.control.forecast` — the forecast as a tip trajectory; :mod:`mpcshare.control.fastpath` —
  the control-rate forecast;
- :mod:`mpcshare.control.preview` — the MPC's preview of the tip reference over its horizon;
- :mod:`mpcshare.control.mpc_follow` — solving the MPC every few steps and following its plan;
- :mod:`mpcshare.control.keepout` — keeping the knife out of the wearer's body zones;
- :mod:`mpcshare.control.fallback` — the last-resort commands when a step fails unexpectedly;
- :mod:`mpcshare.control.arbitration` — α, β and the fusion û = α·û_r + β·û_v;
- :mod:`mpcshare.control.strategies` — the arbitration strategies, one module each, in ``REGISTRY``;
- :mod:`mpcshare.control.setup` — checking a bundle against the controller and building the MPC;
- :mod:`mpcshare.control.workspace` — frames (the base pose) and the workspace box.
"""

from mpcshare.control.controller import SharedController
from mpcshare.control.types import STATUSES, ControlCommand, ControllerConfig

__all__ = ["STATUSES", "ControlCommand", "ControllerConfig", "SharedController"]
